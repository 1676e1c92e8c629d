//! Hesai's angle correction file into the Hesai decoder's [`Calibration`]: the CSV the sensor
//! hands out and Hesai's SDK reads, a header line (`Laser id,Elevation,Azimuth` or
//! `Channel,Elevation,Azimuth`) and one row per channel, numbered from 1, angles in degrees.

use anyhow::{bail, Context, Result};
use kiss_odom_sensors::hesai::{Calibration, MAX_CHANNELS};
use std::path::Path;

/// Reads the angle correction file of a sensor of `channels` channels.
pub fn read(path: &Path, channels: usize) -> Result<Calibration> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    parse(&text, channels).with_context(|| {
        format!(
            "{}: not the angle correction file of a {channels}-channel Hesai",
            path.display()
        )
    })
}

/// Parses the CSV text (see the module doc) of a sensor of `channels` channels.
pub fn parse(text: &str, channels: usize) -> Result<Calibration> {
    if !(1..=MAX_CHANNELS).contains(&channels) {
        bail!("{channels} channels: a Hesai has 1 to {MAX_CHANNELS}");
    }
    let mut seen = vec![false; channels];
    let mut c = Calibration::nominal();
    c.channels = channels;
    for (n, line) in text.lines().enumerate() {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let Some(id) = fields.first().and_then(|f| f.parse::<usize>().ok()) else {
            // The header, or an empty line.
            continue;
        };
        let angle = |i: usize| -> Result<f64> {
            let v: f64 = fields
                .get(i)
                .with_context(|| format!("line {}: fewer than 3 columns", n + 1))?
                .parse()
                .with_context(|| format!("line {}: column {} is not a number", n + 1, i + 1))?;
            Ok(v)
        };
        if !(1..=channels).contains(&id) || seen[id - 1] {
            bail!(
                "line {}: channel {id} is not one of 1..={channels} once",
                n + 1
            );
        }
        seen[id - 1] = true;
        c.elevation_deg[id - 1] = angle(1)?;
        c.azimuth_deg[id - 1] = angle(2)?;
    }
    let missing = seen.iter().filter(|s| !**s).count();
    if missing > 0 {
        bail!("{missing} of the {channels} channels have no row");
    }
    if c.validate().is_err() {
        bail!("an angle is not finite, an elevation beyond 90 or an azimuth beyond 45 degrees");
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn csv(rows: impl Iterator<Item = (usize, f64, f64)>) -> String {
        let mut s = String::from("Laser id,Elevation,Azimuth\n");
        for (i, e, a) in rows {
            s.push_str(&format!("{i},{e},{a}\n"));
        }
        s
    }

    #[test]
    fn rows_in_any_order_fill_their_channels() {
        let text = csv((1..=32)
            .rev()
            .map(|i| (i, 16.0 - i as f64 + 0.125, i as f64 * 0.01)));
        let c = parse(&text, 32).unwrap();
        assert_eq!(c.elevation_deg[0], 15.125);
        assert_eq!(c.elevation_deg[31], -15.875);
        assert_eq!(c.azimuth_deg[9], 0.1);
    }

    #[test]
    fn missing_repeated_and_bad_rows_are_errors() {
        let short = csv((1..=31).map(|i| (i, 0.0, 0.0)));
        assert!(parse(&short, 32)
            .unwrap_err()
            .to_string()
            .contains("1 of the 32"));
        let twice = csv((1..=32).chain([5]).map(|i| (i, 0.0, 0.0)));
        assert!(parse(&twice, 32).is_err());
        let beyond = csv((1..=33).map(|i| (i, 0.0, 0.0)));
        assert!(parse(&beyond, 32).is_err());
        let steep = csv((1..=32).map(|i| (i, if i == 3 { 95.0 } else { 0.0 }, 0.0)));
        assert!(parse(&steep, 32).is_err());
        let text = csv((1..=32).map(|i| (i, 0.0, 0.0))).replace("\n7,0,0", "\n7,x,0");
        assert!(parse(&text, 32).unwrap_err().to_string().contains("line 8"));
        // A 128-channel file: every row read, none left nominal.
        let wide = csv((1..=128).map(|i| (i, 52.5 - i as f64 * 0.8, 10.0 - i as f64 * 0.1)));
        let c = parse(&wide, 128).unwrap();
        assert_eq!((c.channels, c.elevation_deg[127]), (128, 52.5 - 102.4));
        assert!(parse(&wide, 32).is_err());
        assert!(parse(&short, 129).is_err());
    }
}
