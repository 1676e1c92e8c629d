//! Ouster packets to sweeps: layout and identity checks, frame-id sweep boundaries, column
//! bookkeeping for losses and order, then each return to a point.

use super::info::{spacing_fits, SensorInfo, MAX_BEAMS, MAX_COLUMNS};
use super::wire::{Column, Layout, Packet, Profile};
use crate::error::{ConfigError, PacketError};
use crate::sweep::{
    Assembly, Decode, PointMeta, Pushed, Return, SweepEnd, SweepSink, SweepStats, RESYNC_PACKETS,
};
use core::f64::consts::PI;

/// One beam's angles, ready to use.
#[derive(Clone, Copy, Debug, Default)]
struct Beam {
    cos_alt: f64,
    sin_alt: f64,
    cos_az: f64,
    sin_az: f64,
}

/// Ouster packets in, sweeps out (see the module doc of [`crate::ouster`]).
pub struct Decoder {
    layout: Layout,
    beams: [Beam; MAX_BEAMS],
    width: u16,
    frequency_hz: Option<u16>,
    window: (u16, u16),
    rotation: [[f64; 3]; 3],
    translation: [f64; 3],
    /// Beam origin: along the encoder direction, its distance from the lidar axis, height.
    beam_x: f64,
    beam_z: f64,
    beam_distance: f64,
    ids: (Option<u32>, Option<u64>),
    frame: Option<u16>,
    last_closed: Option<u16>,
    seen: [u32; MAX_COLUMNS / 32],
    last_column: Option<u16>,
    /// Packets lost by the frame ids the open frame skipped (given back if its timeline is
    /// abandoned).
    jump_lost: u32,
    /// Consecutive late packets and the last one's frame id.
    late_run: Option<(u32, u16)>,
    asm: Assembly,
}

/// Whether frame id `a` comes after `b` (ids wrap at 2^16).
fn after(a: u16, b: u16) -> bool {
    (a.wrapping_sub(b) as i16) > 0
}

impl Decoder {
    /// A decoder for the sensor `info` describes.
    pub fn new(info: &SensorInfo) -> Result<Self, ConfigError> {
        info.validate()?;
        let mut beams = [Beam::default(); MAX_BEAMS];
        for (b, (alt, az)) in beams
            .iter_mut()
            .zip(info.beam_altitude_deg.iter().zip(&info.beam_azimuth_deg))
        {
            let (alt, az) = (alt * PI / 180.0, -az * PI / 180.0);
            *b = Beam {
                cos_alt: libm::cos(alt),
                sin_alt: libm::sin(alt),
                cos_az: libm::cos(az),
                sin_az: libm::sin(az),
            };
        }
        let m = &info.lidar_to_sensor;
        let rotation = [[m[0], m[1], m[2]], [m[4], m[5], m[6]], [m[8], m[9], m[10]]];
        let translation = [m[3], m[7], m[11]];
        let (beam_x, beam_z) = (info.beam_to_lidar[3], info.beam_to_lidar[11]);
        // As ouster-sdk: the beam origin's distance from the lidar origin.
        let beam_distance = if beam_z == 0.0 {
            beam_x
        } else {
            libm::sqrt(beam_x * beam_x + beam_z * beam_z)
        };
        Ok(Self {
            layout: info.layout(),
            beams,
            width: info.columns_per_frame,
            frequency_hz: info.frequency_hz,
            window: info.column_window,
            rotation,
            translation,
            beam_x,
            beam_z,
            beam_distance,
            ids: (
                info.initialization_id.filter(|&i| i != 0),
                info.serial.filter(|&s| s != 0),
            ),
            frame: None,
            last_closed: None,
            seen: [0; MAX_COLUMNS / 32],
            last_column: None,
            jump_lost: 0,
            late_run: None,
            asm: Assembly::new(),
        })
    }

    /// The packet's valid columns against the metadata: inside the column window, and spaced
    /// in time as its columns per frame and rate say.
    fn check_columns(&self, p: &Packet<'_>) -> Result<(), PacketError> {
        let (mut first, mut last) = (None, None);
        for c in (0..self.layout.columns).map(|i| p.column(i)) {
            if !c.valid() {
                continue;
            }
            let m = c.measurement_id();
            if !self.in_window(m) {
                return Err(PacketError::ColumnWindow);
            }
            let at = (m, c.timestamp_ns());
            first.get_or_insert(at);
            last = Some(at);
        }
        if let (Some((m0, t0)), Some((m1, t1))) = (first, last) {
            if m1 > m0 && t1 > t0 {
                let spacing = (t1 - t0) as f64 / f64::from(m1 - m0);
                if !spacing_fits(self.width, self.frequency_hz, spacing) {
                    return Err(PacketError::ColumnRate);
                }
            }
        }
        Ok(())
    }

    /// Counts a packet older than the sweep; true when it is the [`RESYNC_PACKETS`]-th in a
    /// row whose frame ids stay or move on by one: their timeline is the sensor's now.
    fn late_run_complete(&mut self, fid: u16) -> bool {
        let n = match self.late_run {
            Some((n, last)) if fid == last || fid == last.wrapping_add(1) => n + 1,
            _ => 1,
        };
        self.late_run = Some((n, fid));
        n >= RESYNC_PACKETS
    }

    /// Abandons the open frame's timeline (its missing columns and skipped frame ids were
    /// never lost: the ids jumped); true if a sweep was open and has ended.
    fn resync<S: SweepSink>(&mut self, sink: &mut S) -> bool {
        self.late_run = None;
        self.last_closed = None;
        let open = self.frame.take().is_some();
        if open {
            let stats = self.asm.stats();
            stats.lost_packets = stats.lost_packets.saturating_sub(self.jump_lost);
            self.asm.end(sink, SweepEnd::Resync);
        }
        self.asm.resynced();
        open
    }

    /// The packet layout the metadata announced.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    fn in_window(&self, m: u16) -> bool {
        let (a, b) = self.window;
        if a <= b {
            (a..=b).contains(&m)
        } else {
            m >= a || m <= b
        }
    }

    fn window_len(&self) -> u32 {
        let (a, b) = self.window;
        u32::from(b.wrapping_sub(a)) % u32::from(self.width) + 1
    }

    fn close<S: SweepSink>(&mut self, sink: &mut S, end: SweepEnd) {
        if let Some(f) = self.frame.take() {
            let received: u32 = self.seen.iter().map(|w| w.count_ones()).sum();
            let missing = self.window_len().saturating_sub(received);
            let cpp = self.layout.columns as u32;
            let stats = self.asm.stats();
            stats.lost_packets = stats
                .lost_packets
                .saturating_add(missing.div_ceil(cpp.max(1)));
            self.last_closed = Some(f);
        }
        self.asm.end(sink, end);
    }

    fn accept<S: SweepSink>(&mut self, bytes: &[u8], sink: &mut S) -> Result<Pushed, PacketError> {
        let p = Packet::new_checked(bytes, self.layout)?;
        // Legacy packets carry no identity; eUDP packets must be the metadata's sensor.
        let differs = |ours: Option<u64>, theirs: Option<u64>| matches!((ours, theirs), (Some(a), Some(b)) if a != b);
        if differs(self.ids.0.map(u64::from), p.init_id().map(u64::from))
            || differs(self.ids.1, p.serial())
        {
            return Err(PacketError::MetadataMismatch);
        }
        // A measurement id beyond the frame: the metadata's mode is not the sensor's.
        let columns = (0..self.layout.columns).map(|i| p.column(i));
        if let Some(c) = columns.clone().find(|c| c.measurement_id() >= self.width) {
            return Err(PacketError::MeasurementId {
                id: c.measurement_id(),
                columns: self.width,
            });
        }
        self.check_columns(&p)?;
        let fid = p.frame_id();
        let older = match (self.frame, self.last_closed) {
            (Some(f), _) if f == fid => false,
            (Some(f), _) if after(fid, f) => {
                self.close(sink, SweepEnd::NextFrame);
                return Ok(Pushed::Again);
            }
            (Some(_), _) => true,
            (None, Some(l)) => !after(fid, l),
            (None, None) => false,
        };
        if older {
            if !self.late_run_complete(fid) {
                return Err(PacketError::Late);
            }
            if self.resync(sink) {
                return Ok(Pushed::Again);
            }
        }
        self.late_run = None;
        if self.frame.is_none() {
            let skipped = match self.last_closed {
                Some(l) => u32::from(fid.wrapping_sub(l)).saturating_sub(1),
                None => 0,
            };
            let start = columns
                .clone()
                .find(|c| c.valid())
                .unwrap_or(p.column(0))
                .timestamp_ns();
            self.asm.begin(sink, start, Some(fid));
            let per_frame = self.window_len().div_ceil(self.layout.columns as u32);
            self.jump_lost = skipped.saturating_mul(per_frame);
            let stats = self.asm.stats();
            stats.lost_packets = stats.lost_packets.saturating_add(self.jump_lost);
            self.frame = Some(fid);
            self.seen = [0; MAX_COLUMNS / 32];
            self.last_column = None;
        }
        let start_ns = self.asm.open.map(|s| s.start_ns).unwrap_or(0);
        let mut complete = false;
        for c in columns {
            let m = c.measurement_id();
            if !self.in_window(m) {
                continue;
            }
            let (word, bit) = (usize::from(m) / 32, 1u32 << (m % 32));
            let Some(w) = self.seen.get_mut(word) else {
                continue;
            };
            let repeated = *w & bit != 0;
            *w |= bit;
            if repeated || self.last_column.is_some_and(|l| m < l) {
                let stats = self.asm.stats();
                stats.out_of_order = stats.out_of_order.saturating_add(1);
            }
            self.last_column = Some(m);
            if repeated {
                continue;
            }
            complete |= m == self.window.1;
            if c.valid() {
                let t = (c.timestamp_ns() as i64).wrapping_sub(start_ns as i64) as f64 * 1e-9;
                self.column(&c, m, t, sink);
            }
        }
        let stats = self.asm.stats();
        stats.packets = stats.packets.saturating_add(1);
        if complete {
            self.close(sink, SweepEnd::Complete);
            return Ok(Pushed::Ended);
        }
        Ok(Pushed::Decoded)
    }

    /// The returns of one valid column, as ouster-sdk's `XYZLut` places them.
    fn column<S: SweepSink>(&mut self, c: &Column<'_>, m: u16, time: f64, sink: &mut S) {
        let encoder = 2.0 * PI - f64::from(m) * (2.0 * PI / f64::from(self.width));
        let (ce, se) = (libm::cos(encoder), libm::sin(encoder));
        let dual = self.layout.profile == Profile::Rng19Rfl8Sig16Nir16Dual;
        for (u, b) in self.beams.iter().take(self.layout.beams).enumerate() {
            let r1 = c.range_mm(u);
            let r2 = if dual { c.range2_mm(u) } else { 0 };
            if r1 == 0 && r2 == 0 {
                continue;
            }
            // Direction of the beam: encoder plus beam azimuth, then the altitude.
            let cos_sum = ce * b.cos_az - se * b.sin_az;
            let sin_sum = se * b.cos_az + ce * b.sin_az;
            let d = [cos_sum * b.cos_alt, sin_sum * b.cos_alt, b.sin_alt];
            let o = [
                ce * self.beam_x - d[0] * self.beam_distance,
                se * self.beam_x - d[1] * self.beam_distance,
                -d[2] * self.beam_distance + self.beam_z,
            ];
            let (d, o) = (self.rotate(d), self.rotate(o));
            let o = [
                o[0] + self.translation[0],
                o[1] + self.translation[1],
                o[2] + self.translation[2],
            ];
            let mut emit = |range: u32, ret, intensity| {
                let r = f64::from(range);
                let xyz = [0, 1, 2].map(|k| d[k] * 0.001 * r + o[k] * 0.001);
                let meta = PointMeta {
                    ring: u as u16,
                    column: m,
                    ret,
                    intensity,
                };
                self.asm.push(sink, xyz, time, meta);
            };
            if r1 != 0 {
                emit(r1, Return::First, c.reflectivity(u));
            }
            if r2 != 0 {
                emit(r2, Return::Second, c.reflectivity2(u));
            }
        }
    }

    fn rotate(&self, v: [f64; 3]) -> [f64; 3] {
        self.rotation
            .map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2])
    }
}

impl Decode for Decoder {
    fn push<S: SweepSink>(&mut self, bytes: &[u8], sink: &mut S) -> Result<Pushed, PacketError> {
        let r = self.accept(bytes, sink);
        self.asm.counted(r)
    }
    fn finish<S: SweepSink>(&mut self, sink: &mut S) {
        self.close(sink, SweepEnd::Finished);
    }
    fn between_sweeps(&self) -> &SweepStats {
        &self.asm.pending
    }
}
