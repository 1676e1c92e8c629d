//! Hesai's angle correction file into the PandarXT-32 decoder's [`Calibration`]: the CSV the
//! sensor hands out and Hesai's SDK reads, a header line (`Laser id,Elevation,Azimuth` or
//! `Channel,Elevation,Azimuth`) and one row per channel, numbered from 1, angles in degrees.

use anyhow::{bail, Context, Result};
use kiss_odom_sensors::hesai::{Calibration, CHANNELS};
use std::path::Path;

/// Reads an angle correction file.
pub fn read(path: &Path) -> Result<Calibration> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    parse(&text).with_context(|| {
        format!(
            "{}: not a PandarXT-32 angle correction file",
            path.display()
        )
    })
}

/// Parses the CSV text (see the module doc).
pub fn parse(text: &str) -> Result<Calibration> {
    let mut seen = [false; CHANNELS];
    let mut c = Calibration::nominal();
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
        if !(1..=CHANNELS).contains(&id) || seen[id - 1] {
            bail!(
                "line {}: channel {id} is not one of 1..={CHANNELS} once",
                n + 1
            );
        }
        seen[id - 1] = true;
        c.elevation_deg[id - 1] = angle(1)?;
        c.azimuth_deg[id - 1] = angle(2)?;
    }
    let missing = seen.iter().filter(|s| !**s).count();
    if missing > 0 {
        bail!("{missing} of the {CHANNELS} channels have no row");
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
        let c = parse(&text).unwrap();
        assert_eq!(c.elevation_deg[0], 15.125);
        assert_eq!(c.elevation_deg[31], -15.875);
        assert_eq!(c.azimuth_deg[9], 0.1);
    }

    #[test]
    fn missing_repeated_and_bad_rows_are_errors() {
        let short = csv((1..=31).map(|i| (i, 0.0, 0.0)));
        assert!(parse(&short)
            .unwrap_err()
            .to_string()
            .contains("1 of the 32"));
        let twice = csv((1..=32).chain([5]).map(|i| (i, 0.0, 0.0)));
        assert!(parse(&twice).is_err());
        let beyond = csv((1..=33).map(|i| (i, 0.0, 0.0)));
        assert!(parse(&beyond).is_err());
        let steep = csv((1..=32).map(|i| (i, if i == 3 { 95.0 } else { 0.0 }, 0.0)));
        assert!(parse(&steep).is_err());
        let text = csv((1..=32).map(|i| (i, 0.0, 0.0))).replace("\n7,0,0", "\n7,x,0");
        assert!(parse(&text).unwrap_err().to_string().contains("line 8"));
    }
}
