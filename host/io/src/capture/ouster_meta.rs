//! Ouster metadata JSON (what the sensor's `get_metadata` returns and `ouster-cli` saves next
//! to a recording) into the decoder's [`SensorInfo`].
//!
//! Two layouts exist: the flat one of firmware up to 2.3 (`beam_altitude_angles` at the top,
//! `data_format`, `prod_sn`) and the nested one of later firmware (`beam_intrinsics`,
//! `lidar_intrinsics`, `lidar_data_format`, `sensor_info`, `config_params`). Both are read;
//! where a field is in neither, the error names it. Metadata that contradicts itself or
//! physics is refused naming the field: `columns_per_frame` against `lidar_mode`, transforms
//! that are not rigid, beam angles and origins out of bounds
//! ([`SensorInfo::validate`]); a column window under an eighth of a turn is a warning. What
//! only the packets can contradict (the column window, the columns' spacing, the sensor's
//! identity) the decoder checks.

use anyhow::{anyhow, bail, Context, Result};
use kiss_odom_sensors::ouster::{Profile, SensorInfo, MAX_BEAMS};
use serde::Deserialize;
use std::path::Path;

/// The sensor's metadata: the decoder's numbers and what a person needs to tell sensors apart.
#[derive(Clone, Debug, PartialEq)]
pub struct OusterMeta {
    /// What the decoder takes.
    pub info: SensorInfo,
    /// Product line, e.g. `OS-1-128`.
    pub prod_line: String,
    /// Serial number as written.
    pub serial: String,
    /// Firmware (`build_rev`).
    pub firmware: String,
    /// UDP port of the lidar packets, if the metadata says.
    pub udp_port_lidar: Option<u16>,
    /// UDP port of the IMU packets, if the metadata says (0 is "not set").
    pub udp_port_imu: Option<u16>,
    /// `lidar_mode`, e.g. `1024x10`.
    pub lidar_mode: String,
    /// What is odd but decodes correctly, one line each.
    pub warnings: Vec<String>,
}

#[derive(Deserialize, Default)]
struct Beams {
    beam_altitude_angles: Option<Vec<f64>>,
    beam_azimuth_angles: Option<Vec<f64>>,
    beam_to_lidar_transform: Option<Vec<f64>>,
    lidar_origin_to_beam_origin_mm: Option<f64>,
}

#[derive(Deserialize, Default)]
struct DataFormat {
    columns_per_frame: Option<u16>,
    columns_per_packet: Option<u16>,
    pixels_per_column: Option<usize>,
    pixel_shift_by_row: Option<Vec<i16>>,
    column_window: Option<(u16, u16)>,
    udp_profile_lidar: Option<String>,
}

#[derive(Deserialize, Default)]
struct Ident {
    prod_line: Option<String>,
    prod_sn: Option<serde_json::Value>,
    build_rev: Option<String>,
    initialization_id: Option<u32>,
}

#[derive(Deserialize, Default)]
struct Config {
    udp_profile_lidar: Option<String>,
    udp_port_lidar: Option<u16>,
    udp_port_imu: Option<u16>,
    lidar_mode: Option<String>,
}

#[derive(Deserialize, Default)]
struct LidarIntrinsics {
    lidar_to_sensor_transform: Option<Vec<f64>>,
}

#[derive(Deserialize)]
struct Raw {
    #[serde(flatten)]
    beams: Beams,
    #[serde(flatten)]
    ident: Ident,
    #[serde(flatten)]
    config: Config,
    data_format: Option<DataFormat>,
    lidar_to_sensor_transform: Option<Vec<f64>>,
    beam_intrinsics: Option<Beams>,
    lidar_intrinsics: Option<LidarIntrinsics>,
    lidar_data_format: Option<DataFormat>,
    sensor_info: Option<Ident>,
    config_params: Option<Config>,
}

fn matrix(v: Option<Vec<f64>>, name: &str) -> Result<[f64; 16]> {
    let v = v.ok_or_else(|| anyhow!("no {name}"))?;
    v.try_into()
        .map_err(|v: Vec<f64>| anyhow!("{name} has {} numbers, not 16", v.len()))
}

fn table<T: Copy>(v: Vec<T>, name: &str) -> Result<kiss_odom_sensors::heapless::Vec<T, MAX_BEAMS>> {
    kiss_odom_sensors::heapless::Vec::from_slice(&v)
        .map_err(|_| anyhow!("{name} has {} entries, above {MAX_BEAMS}", v.len()))
}

/// Parses metadata JSON text.
pub fn parse(text: &str) -> Result<OusterMeta> {
    let raw: Raw = serde_json::from_str(text).context("not Ouster metadata JSON")?;
    let beams = raw.beam_intrinsics.unwrap_or(raw.beams);
    let format = raw
        .lidar_data_format
        .or(raw.data_format)
        .ok_or_else(|| anyhow!("no data_format / lidar_data_format"))?;
    let ident = raw.sensor_info.unwrap_or(raw.ident);
    let config = raw.config_params.unwrap_or(raw.config);
    let altitude = beams
        .beam_altitude_angles
        .ok_or_else(|| anyhow!("no beam_altitude_angles"))?;
    let azimuth = beams
        .beam_azimuth_angles
        .ok_or_else(|| anyhow!("no beam_azimuth_angles"))?;
    let beam_to_lidar = match beams.beam_to_lidar_transform {
        Some(m) => matrix(Some(m), "beam_to_lidar_transform")?,
        None => {
            let d = beams
                .lidar_origin_to_beam_origin_mm
                .ok_or_else(|| anyhow!("no lidar_origin_to_beam_origin_mm"))?;
            let mut m = [0.0; 16];
            (m[0], m[5], m[10], m[15], m[3]) = (1.0, 1.0, 1.0, 1.0, d);
            m
        }
    };
    let lidar_to_sensor = matrix(
        raw.lidar_intrinsics
            .and_then(|l| l.lidar_to_sensor_transform)
            .or(raw.lidar_to_sensor_transform),
        "lidar_to_sensor_transform",
    )?;
    // Firmware before 2.2 has no profile field: those sensors send legacy packets.
    let profile_name = format
        .udp_profile_lidar
        .or(config.udp_profile_lidar)
        .unwrap_or_else(|| "LEGACY".into());
    let profile = Profile::from_name(&profile_name)
        .ok_or_else(|| anyhow!("udp_profile_lidar {profile_name} is not decoded here"))?;
    let columns_per_frame = format
        .columns_per_frame
        .ok_or_else(|| anyhow!("no columns_per_frame"))?;
    if let Some(n) = format.pixels_per_column {
        if n != altitude.len() {
            bail!(
                "pixels_per_column {n} but {} beam altitude angles",
                altitude.len()
            );
        }
    }
    let lidar_mode = config.lidar_mode.unwrap_or_default();
    // `1024x10`: columns per frame and turns per second.
    let mode: Option<(u16, u16)> = lidar_mode
        .split_once('x')
        .and_then(|(w, hz)| Some((w.parse().ok()?, hz.parse().ok()?)));
    if let Some((w, _)) = mode.filter(|&(w, _)| w != columns_per_frame) {
        bail!("columns_per_frame {columns_per_frame} but lidar_mode {lidar_mode} ({w} columns)");
    }
    let serial = match ident.prod_sn {
        Some(serde_json::Value::String(s)) => s,
        Some(serde_json::Value::Number(n)) => n.to_string(),
        _ => String::new(),
    };
    let info = SensorInfo {
        profile,
        columns_per_frame,
        columns_per_packet: format.columns_per_packet.unwrap_or(16),
        column_window: format
            .column_window
            .unwrap_or((0, columns_per_frame.saturating_sub(1))),
        beam_altitude_deg: table(altitude, "beam_altitude_angles")?,
        beam_azimuth_deg: table(azimuth, "beam_azimuth_angles")?,
        pixel_shift_by_row: table(
            format.pixel_shift_by_row.unwrap_or_default(),
            "pixel_shift_by_row",
        )?,
        beam_to_lidar,
        lidar_to_sensor,
        initialization_id: ident.initialization_id,
        serial: serial.parse().ok(),
        frequency_hz: mode.map(|(_, hz)| hz),
    };
    info.validate().map_err(|e| anyhow!("{e}"))?;
    let mut warnings = Vec::new();
    let (a, b) = info.column_window;
    let window = usize::from(b.wrapping_sub(a)) % usize::from(columns_per_frame) + 1;
    if window * 8 < usize::from(columns_per_frame) {
        warnings.push(format!(
            "column_window [{a}, {b}] holds {window} of the {columns_per_frame} columns: each \
             sweep covers {:.0} degrees of the turn",
            360.0 * window as f64 / f64::from(columns_per_frame)
        ));
    }
    Ok(OusterMeta {
        info,
        prod_line: ident.prod_line.unwrap_or_default(),
        serial,
        firmware: ident.build_rev.unwrap_or_default(),
        udp_port_lidar: config.udp_port_lidar,
        udp_port_imu: config.udp_port_imu.filter(|&p| p != 0),
        lidar_mode,
        warnings,
    })
}

/// Reads the metadata file at `path`; errors name the file.
pub fn read(path: &Path) -> Result<OusterMeta> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    parse(&text).with_context(|| format!("{}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    const NESTED: &str = r#"{
      "beam_intrinsics": {"beam_altitude_angles": [10.0, -10.0], "beam_azimuth_angles": [1.0, -1.0],
        "beam_to_lidar_transform": [1,0,0,15.8, 0,1,0,0, 0,0,1,3.0, 0,0,0,1],
        "lidar_origin_to_beam_origin_mm": 15.8},
      "lidar_intrinsics": {"lidar_to_sensor_transform": [-1,0,0,0, 0,-1,0,0, 0,0,1,36.18, 0,0,0,1]},
      "lidar_data_format": {"columns_per_frame": 512, "columns_per_packet": 16, "pixels_per_column": 2,
        "pixel_shift_by_row": [12, 4], "column_window": [0, 511],
        "udp_profile_lidar": "RNG19_RFL8_SIG16_NIR16"},
      "sensor_info": {"prod_line": "OS-1-2", "prod_sn": "122201000998", "initialization_id": 7},
      "config_params": {"udp_port_lidar": 7502, "udp_port_imu": 0, "lidar_mode": "512x10"}
    }"#;

    #[test]
    fn nested_metadata_of_newer_firmware_reads_like_the_flat_one() {
        let m = parse(NESTED).unwrap();
        assert_eq!(m.info.profile, Profile::Rng19Rfl8Sig16Nir16);
        assert_eq!(m.info.beam_to_lidar[11], 3.0);
        assert_eq!(m.info.lidar_to_sensor[11], 36.18);
        assert_eq!(
            (m.info.serial, m.info.initialization_id),
            (Some(122201000998), Some(7))
        );
        assert_eq!(
            (m.udp_port_lidar, m.udp_port_imu, m.info.columns_per_frame),
            (Some(7502), None, 512)
        );
    }

    #[test]
    fn missing_and_inconsistent_fields_are_named() {
        let e = parse(&NESTED.replace("beam_altitude_angles", "x")).unwrap_err();
        assert!(format!("{e:#}").contains("beam_altitude_angles"), "{e:#}");
        let e = parse(&NESTED.replace("\"pixels_per_column\": 2", "\"pixels_per_column\": 64"))
            .unwrap_err();
        assert!(format!("{e:#}").contains("pixels_per_column 64"), "{e:#}");
        let e = parse(&NESTED.replace("\"lidar_mode\": \"512x10\"", "\"lidar_mode\": \"1024x10\""))
            .unwrap_err();
        assert!(
            format!("{e:#}").contains("columns_per_frame 512 but lidar_mode 1024x10"),
            "{e:#}"
        );
        let e =
            parse(&NESTED.replace("[-1,0,0,0, 0,-1,0,0,", "[-1.5,0,0,0, 0,-1,0,0,")).unwrap_err();
        assert!(
            format!("{e:#}").contains("lidar_to_sensor_transform"),
            "{e:#}"
        );
        let e = parse(&NESTED.replace(
            "1,0,0,15.8, 0,1,0,0, 0,0,1,3.0, 0,0,0,1",
            "1,0,0,15.8, 0,1,0,0, 0,0,1,3.0, 0,0,1,1",
        ))
        .unwrap_err();
        assert!(
            format!("{e:#}").contains("beam_to_lidar_transform"),
            "{e:#}"
        );
        let e = parse(&NESTED.replace("[10.0, -10.0]", "[10.0, -100.0]")).unwrap_err();
        assert!(format!("{e:#}").contains("beam_altitude_angles"), "{e:#}");
        let m =
            parse(&NESTED.replace("\"column_window\": [0, 511]", "\"column_window\": [500, 3]"))
                .unwrap();
        assert!(
            m.warnings[0].contains("holds 16 of the 512 columns"),
            "{:?}",
            m.warnings
        );
        assert!(parse(NESTED).unwrap().warnings.is_empty());
        let e = parse(&NESTED.replace("RNG19_RFL8_SIG16_NIR16", "FUSA_RNG15")).unwrap_err();
        assert!(format!("{e:#}").contains("FUSA_RNG15"), "{e:#}");
        assert!(parse("[1, 2]").is_err());
    }
}
