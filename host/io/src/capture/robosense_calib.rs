//! A Robosense unit's laser angles for its decoder: the `angle.csv` Robosense ships with the
//! unit (one `vertical,horizontal` line in degrees a laser, as rs_driver's
//! `ChanAngles::loadFromFile` reads it), or the first DIFOP packet in the recording (port
//! 7788), which carries the same angles.

use super::pcap::{self, Datagram};
use anyhow::{bail, Context, Result};
use kiss_odom_sensors::robosense::{wire, Calibration, Laser, Model};
use std::path::Path;

/// Robosense's default DIFOP port.
pub const DIFOP_PORT: u16 = 7788;
/// Robosense's default MSOP (points) port.
pub const MSOP_PORT: u16 = 6699;

/// Parses an `angle.csv` of `model`'s lasers.
pub fn parse_csv(text: &str, model: Model) -> Result<Calibration> {
    let mut lasers = kiss_odom_sensors::heapless::Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let mut fields = line.split(',').map(str::trim);
        let num = |f: Option<&str>, what: &str| -> Result<f64> {
            let f = f.unwrap_or("0");
            f.parse()
                .with_context(|| format!("line {}: {what} {f:?} is not a number", n + 1))
        };
        let laser = Laser {
            vertical_deg: num(fields.next(), "vertical angle")?,
            horizontal_deg: num(fields.next(), "horizontal angle")?,
        };
        if lasers.push(laser).is_err() {
            bail!(
                "more than {} lines",
                kiss_odom_sensors::robosense::MAX_LASERS
            );
        }
    }
    // An angle file does not say the RS-Airy's install mode: its firing table is rs_driver's
    // default.
    let c = Calibration {
        lasers,
        dual: None,
        install: Default::default(),
    };
    if c.lasers.len() != model.lasers() {
        bail!(
            "{} lasers, where a {} has {}",
            c.lasers.len(),
            model.name(),
            model.lasers()
        );
    }
    c.validate(model)
        .map_err(|e| anyhow::anyhow!("{e} (angles beyond +-90 degrees or not finite)"))?;
    Ok(c)
}

/// Reads an `angle.csv`; errors name the file.
pub fn read(path: &Path, model: Model) -> Result<Calibration> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    parse_csv(&text, model).with_context(|| format!("{}", path.display()))
}

/// The angles of the first DIFOP packet of the recording at `path` (any port: the packet's
/// id tells it), or `None` if it has none.
pub fn from_capture(path: &Path, model: Model) -> Result<Option<Calibration>> {
    let mut cap = pcap::open(path)?;
    while let Some(Datagram { payload, .. }) = cap.next_datagram()? {
        if let Some(c) = from_payload(&payload, model) {
            return c
                .map(Some)
                .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()));
        }
    }
    Ok(None)
}

/// The angles of `payload` if it is a DIFOP packet; an error says they are not `model`'s.
pub fn from_payload(payload: &[u8], model: Model) -> Option<Result<Calibration>> {
    let d = wire::Difop::new_checked(payload).ok()?;
    Some(Calibration::from_difop(model, &d).map_err(|e| {
        anyhow::anyhow!(
            "the DIFOP packet's angles are not a {}'s: {e}",
            model.name()
        )
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_angle_file_gives_each_laser_its_two_angles() {
        let text: String = (0..32)
            .map(|i| format!("{},{}\n", i as f64 - 16.0, 0.5))
            .collect();
        let c = parse_csv(&text, Model::Helios).unwrap();
        assert_eq!(c.lasers.len(), 32);
        assert_eq!(c.lasers[3].vertical_deg, -13.0);
        assert_eq!(c.lasers[3].horizontal_deg, 0.5);
        let e = format!("{:#}", parse_csv(&text, Model::Ruby).unwrap_err());
        assert!(e.contains("32 lasers, where a RS-Ruby has 128"), "{e}");
        let e = format!("{:#}", parse_csv("x,1\n", Model::Rs16).unwrap_err());
        assert!(e.contains("line 1: vertical angle \"x\""), "{e}");
        let bad: String = (0..16).map(|_| "95,0\n").collect();
        assert!(parse_csv(&bad, Model::Rs16).is_err());
    }
}
