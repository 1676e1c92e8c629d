//! `--set SECTION.KEY=VALUE`: any setting from the command line, as the settings file would
//! give it, applied after the file and before the named flags.

use super::Settings;
use anyhow::{anyhow, bail, Context, Result};
use kiss_odom_core::{Capacities, Config};

impl Settings {
    /// These settings with each assignment applied in order. `SECTION.KEY=VALUE` takes the
    /// value as TOML (`1`, `0.5`, `true`, `[0, 0, 0.1, 0, 0, 180]`; a bare word is a string);
    /// `runtime.memory_limit` also takes a size (`512M`, `8G`). `capacities=full|small|tiny`
    /// fixes every capacity to a named set; `tiny` also sets the parameters it was sized for
    /// (`Config::tiny`: max range 50 m, voxel 2 m, 10 points a voxel), which later
    /// assignments and flags may change. Unknown keys and values of the wrong kind are refused,
    /// naming the assignment.
    pub fn with_set(&self, assignments: &[String]) -> Result<Self> {
        let mut s = self.clone();
        for a in assignments {
            let (key, value) = a
                .split_once('=')
                .map(|(k, v)| (k.trim(), v.trim()))
                .ok_or_else(|| anyhow!("--set {a}: give SECTION.KEY=VALUE"))?;
            s = match key {
                "capacities" => s.with_named_capacities(value),
                "pipeline.preset" => bail!("--set {a}: the preset is --preset"),
                _ => {
                    let (section, name) = key
                        .split_once('.')
                        .ok_or_else(|| anyhow!("--set {a}: give SECTION.KEY=VALUE"))?;
                    let mut inner = toml::Table::new();
                    inner.insert(name.into(), value_of(key, value));
                    let mut over = toml::Table::new();
                    over.insert(section.into(), toml::Value::Table(inner));
                    s.overlaid(over)
                }
            }
            .with_context(|| format!("--set {a}"))?;
        }
        Ok(s)
    }

    /// Every capacity fixed to the set `name` names.
    fn with_named_capacities(mut self, name: &str) -> Result<Self> {
        let caps = match name {
            "full" => Capacities::FULL_SCALE,
            "small" => Capacities::SMALL,
            "tiny" => {
                let t = Config::<f64>::tiny();
                self.data.max_range = t.max_range;
                self.mapping.voxel_size = Some(t.voxel_size);
                self.mapping.max_points_per_voxel = t.max_points_per_voxel;
                Capacities::TINY
            }
            other => bail!("{other}: not a named set of capacities (full, small, tiny)"),
        };
        self.capacities = caps.into();
        Ok(self)
    }
}

/// The TOML value `text` reads as; a size for the memory limit; else the text as a string.
fn value_of(key: &str, text: &str) -> toml::Value {
    if key == "runtime.memory_limit" {
        if let Ok(Ok(bytes)) = parse_size(text).map(i64::try_from) {
            return toml::Value::Integer(bytes);
        }
    }
    toml::from_str::<toml::Table>(&format!("v = {text}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(text.into()))
}

/// A size in bytes: a number with an optional K, M, G or T (powers of 1024; `B`, `iB` and
/// lower case accepted).
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let t = t
        .strip_suffix("iB")
        .or_else(|| t.strip_suffix('B'))
        .unwrap_or(t);
    let (digits, shift) = match t.chars().last().map(|c| c.to_ascii_uppercase()) {
        Some('K') => (&t[..t.len() - 1], 10),
        Some('M') => (&t[..t.len() - 1], 20),
        Some('G') => (&t[..t.len() - 1], 30),
        Some('T') => (&t[..t.len() - 1], 40),
        _ => (t, 0),
    };
    let n: f64 = digits
        .trim()
        .parse()
        .map_err(|_| format!("{text}: not a size (e.g. 512M, 8G)"))?;
    let bytes = n * (1u64 << shift) as f64;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(format!("{text}: not a size of at least one byte"));
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::{DegeneracyMode, PoseTime, Scalar};

    fn set(args: &[&str]) -> Result<Settings> {
        let a: Vec<String> = args.iter().map(|s| s.to_string()).collect();
        Settings::default().with_set(&a)
    }

    #[test]
    fn any_key_of_the_file_is_set_by_name_and_later_assignments_win() {
        let s = set(&[
            "registration.degeneracy=robust",
            "registration.plane_gate=1",
            "data.deskew=false",
            "imu.extrinsic=[0, 0, 0.1, 0, 0, 180]",
            "runtime.scalar=f32",
            "runtime.memory_limit=2G",
            "output.pose_time=middle",
            "input.cut_angle=-90",
            "data.min_range=2",
            "data.min_range=3",
        ])
        .unwrap();
        assert_eq!(s.registration.degeneracy, DegeneracyMode::Robust);
        assert_eq!(s.registration.plane_gate, 1.0);
        assert!(!s.data.deskew);
        assert_eq!(s.imu.extrinsic, [0.0, 0.0, 0.1, 0.0, 0.0, 180.0]);
        assert_eq!(s.runtime.scalar, Scalar::F32);
        assert_eq!(s.runtime.memory_limit, Some(2 << 30));
        assert_eq!(s.output.pose_time, PoseTime::Middle);
        assert_eq!(s.input.cut_angle, Some(-90.0));
        assert_eq!(s.data.min_range, 3.0);
        let untouched = Settings::default();
        assert_eq!(s.mapping, untouched.mapping);
    }

    #[test]
    fn named_capacities_fix_every_buffer_and_tiny_its_parameters() {
        let s = set(&["capacities=small"]).unwrap();
        assert_eq!(s.capacities, Capacities::SMALL.into());
        assert!(!s.grows());
        let s = set(&["capacities=tiny", "data.max_range=40"]).unwrap();
        assert_eq!(s.capacities, Capacities::TINY.into());
        assert_eq!((s.data.max_range, s.mapping.voxel_size), (40.0, Some(2.0)));
        assert_eq!(s.mapping.max_points_per_voxel, 10);
    }

    #[test]
    fn a_wrong_assignment_is_refused_naming_it() {
        for (bad, says) in [
            ("registration.plane_gat=1", "unknown field"),
            (
                "registration.plane_gate=high",
                "registration.plane_gate=high",
            ),
            ("capacities=huge", "not a named set"),
            ("pipeline.preset=accurate", "--preset"),
            ("deskew", "SECTION.KEY=VALUE"),
            ("deskew=false", "SECTION.KEY=VALUE"),
            ("nosection.key=1", "unknown field"),
        ] {
            let e = format!("{:#}", set(&[bad]).unwrap_err());
            assert!(e.contains(says) && e.contains("--set"), "{bad}: {e}");
        }
    }

    #[test]
    fn sizes_take_powers_of_1024() {
        assert_eq!(parse_size("512M"), Ok(512 << 20));
        assert_eq!(parse_size("1.5GiB"), Ok(3 << 29));
        assert_eq!(parse_size("4096"), Ok(4096));
        assert!(parse_size("lots").is_err() && parse_size("0").is_err());
    }
}
