//! What `listen-poses` writes: `poses_kitti.txt` through `run`'s writer, `frames.csv` (a row
//! per sweep with the receiver's figures and running counters) and `summary.json`, which
//! records the others as `run`'s does ([`kiss_odom_io::write::outputs`]).

use super::received::{Received, Undecodable};
use anyhow::Result;
use kiss_odom_core::Flag;
use kiss_odom_io::write::outputs::{Digests, Outputs};
use kiss_odom_sensors::pose_datagram::{Counters, Link};
use serde::ser::{Serialize, SerializeStruct, Serializer};
use std::net::SocketAddr;
use std::path::Path;

/// Every file `listen-poses` writes.
pub const OUTPUTS: [&str; 3] = ["poses_kitti.txt", "frames.csv", "summary.json"];

/// The receiver's [`Counters`] as named columns and JSON fields.
pub struct Totals(pub Counters);

impl Serialize for Totals {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut st = s.serialize_struct("Counters", 8)?;
        for (name, v) in self.0.named() {
            st.serialize_field(name, &v)?;
        }
        st.end()
    }
}

/// One line of `frames.csv` before the counter columns.
#[derive(serde::Serialize)]
struct Row {
    sweep: u32,
    start_ns: u64,
    points: u32,
    status: String,
    iterations: u16,
    sweep_lost: u32,
    link: String,
}

/// `ok`, or the names of the set bits joined by `|`; a bit without a name is `bitN`.
fn names(bits: u16, known: impl IntoIterator<Item = (u16, &'static str)>) -> String {
    let mut rest = bits;
    let mut parts: Vec<String> = Vec::new();
    for (bit, name) in known {
        if bits & bit != 0 {
            parts.push(name.into());
            rest &= !bit;
        }
    }
    parts.extend(
        (0..16)
            .filter(|k| rest & (1 << k) != 0)
            .map(|k| format!("bit{k}")),
    );
    if parts.is_empty() {
        "ok".into()
    } else {
        parts.join("|")
    }
}

/// `summary.json`.
#[derive(serde::Serialize)]
pub struct Summary {
    /// The address listened on.
    pub bind: String,
    /// Sweeps received (duplicates not counted).
    pub sweeps: usize,
    /// The first sweep received.
    pub first_sweep: Option<u32>,
    /// The last sweep received.
    pub last_sweep: Option<u32>,
    /// Sweeps between the first and the last whose datagram did not come.
    pub missing: u64,
    /// Their indices (see `received::MISSING_LISTED`).
    pub missing_sweeps: Vec<u32>,
    /// Datagrams of a sweep that had already come.
    pub duplicates: u64,
    /// Datagrams that came after a later sweep's.
    pub out_of_order: u64,
    /// Datagrams of any kind.
    pub datagrams: u64,
    /// Datagrams that were not pose datagrams, by reason.
    pub undecodable: Undecodable,
    /// The receiver's counters as of the last sweep (they are running totals).
    pub counters: Option<Totals>,
    /// Who sent datagrams, and how many.
    pub senders: Vec<serde_json::Value>,
    /// Whether SIGINT or SIGTERM stopped the listening.
    pub interrupted: bool,
    /// Warnings printed: what was lost on the way or changed poses (see [`Self::warned`]).
    pub warnings: usize,
    /// Their text.
    #[serde(skip)]
    pub warned: Vec<String>,
    /// The other files written in the output folder and the SHA-256 of each: what a later
    /// command replaces as an earlier one's.
    pub outputs: Digests,
}

/// What each counter but `packets` means when it is not 0.
fn meaning(counter: &str) -> &'static str {
    match counter {
        "lost" => "packets missing in the sensor's sequence",
        "bad" => "packets the receiver's decoder refused",
        "foreign" => "datagrams from a second sender, skipped",
        "wrong_size" => "datagrams of the wrong length or fragments, skipped",
        "overflow" => "frames dropped at the receiver's full ring",
        "unsent" => "pose datagrams the receiver could not send",
        "frame_errors" => "sweeps the core refused (pose carried on the motion model)",
        _ => "",
    }
}

/// One line per kind of loss: pose datagrams missing or undecodable here, and each of the
/// receiver's loss counters that is not 0 (the sweeps are flagged in `frames.csv`'s `link`).
fn warnings(missing: u64, undecodable: u64, counters: Option<&Counters>) -> Vec<String> {
    let mut w = Vec::new();
    if missing > 0 {
        w.push(format!(
            "{missing} pose datagram(s) lost on the way (missing_sweeps in summary.json)"
        ));
    }
    if undecodable > 0 {
        w.push(format!(
            "{undecodable} datagram(s) that are not pose datagrams, skipped"
        ));
    }
    for (name, n) in counters.map(Counters::named).into_iter().flatten() {
        if name != "packets" && n > 0 {
            w.push(format!(
                "the receiver counted {name}={n}: {}",
                meaning(name)
            ));
        }
    }
    w
}

impl Summary {
    /// The summary of `r`, received on `bound`.
    pub fn of(bound: SocketAddr, r: &Received, interrupted: bool) -> Self {
        let (missing_sweeps, missing) = r.missing();
        let last = r.sweeps.values().next_back().map(|d| d.counters);
        let warned = warnings(missing, r.undecodable.total(), last.as_ref());
        Self {
            bind: bound.to_string(),
            sweeps: r.sweeps.len(),
            first_sweep: r.sweeps.keys().next().copied(),
            last_sweep: r.sweeps.keys().next_back().copied(),
            missing,
            missing_sweeps,
            duplicates: r.duplicates,
            out_of_order: r.out_of_order,
            datagrams: r.datagrams,
            undecodable: r.undecodable,
            counters: last.map(Totals),
            senders: r
                .senders
                .iter()
                .map(|(a, n)| serde_json::json!({ "address": a.to_string(), "datagrams": n }))
                .collect(),
            interrupted,
            warnings: warned.len(),
            warned,
            outputs: Digests::new(),
        }
    }

    /// The line printed at the end.
    pub fn line(&self) -> String {
        let mut line = format!(
            "listen-poses: {} sweeps, {} missing",
            self.sweeps, self.missing
        );
        for (n, what) in [
            (self.duplicates, "duplicate"),
            (self.undecodable.total(), "undecodable"),
        ] {
            if n > 0 {
                line += &format!(", {n} {what}");
            }
        }
        if let Some(t) = &self.counters {
            let c: Vec<String> =
                t.0.named()
                    .iter()
                    .map(|(k, v)| format!("{k}={v}"))
                    .collect();
            line += &format!(", counters: {}", c.join(" "));
        }
        line
    }
}

/// Writes the outputs into `dir`: `summary.json` always, the others when a sweep came (as
/// `run` writes no pose file without a pose).
pub fn write(dir: &Path, s: &mut Summary, r: &Received) -> Result<()> {
    let mut out = Outputs::new(dir);
    if !r.sweeps.is_empty() {
        let rows: Vec<[f64; 12]> = r.sweeps.values().map(|d| d.pose).collect();
        let kitti = kiss_odom_io::poses::format_kitti_rows(&rows);
        out.write("poses_kitti.txt", kitti.as_bytes())?;
        out.write_with("frames.csv", |w| {
            let mut csv = csv::Writer::from_writer(w);
            for d in r.sweeps.values() {
                let row = Row {
                    sweep: d.sweep,
                    start_ns: d.start_ns,
                    points: d.points,
                    status: names(d.status, Flag::ALL.map(|f| (f as u16, f.name()))),
                    iterations: d.iterations,
                    sweep_lost: d.sweep_lost,
                    link: names(d.link, Link::ALL.map(|l| (l as u16, l.name()))),
                };
                csv.serialize((row, Totals(d.counters)))?;
            }
            csv.flush()?;
            Ok(())
        })?;
    }
    s.outputs = out.record().clone();
    out.write_summary(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use kiss_odom_core::Status;

    #[test]
    fn bits_are_named_as_the_core_names_them_and_unknown_bits_are_kept() {
        let flags = || Flag::ALL.map(|f| (f as u16, f.name()));
        let s = Status::OK.with(Flag::Degenerate).with(Flag::Capacity);
        assert_eq!(names(s.bits(), flags()), s.to_string());
        assert_eq!(names(0, flags()), "ok");
        assert_eq!(names(1 << 15 | 1, flags()), "timestamps_ignored|bit15");
        let link = Link::Gap as u16 | Link::Bad as u16;
        assert_eq!(
            names(link, Link::ALL.map(|l| (l as u16, l.name()))),
            "gap|bad"
        );
    }
}
