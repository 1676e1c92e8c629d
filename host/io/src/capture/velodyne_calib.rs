//! Velodyne per-laser calibration files into the decoder's [`Calibration`]: the ROS YAML
//! (`velodyne_pointcloud`, also what velodyne-decoder ships) and VeloView's XML.
//!
//! YAML angles are radians and offsets metres; XML angles are degrees and offsets centimetres.
//! Both store the azimuth correction with the opposite sign of
//! [`Laser::azimuth_offset_deg`](kiss_odom_sensors::velodyne::Laser::azimuth_offset_deg).
//! The HDL-64E's two-point distance correction is read when a laser has both near-point
//! offsets (`dist_correction_x`/`_y`, `distCorrectionX_`/`Y_`) non-zero, as velodyne-decoder
//! reads it; the intensity terms (focal distance and slope) are ignored.

use anyhow::{anyhow, bail, Context, Result};
use kiss_odom_sensors::velodyne::{Calibration, Laser, MAX_LASERS};
use serde::Deserialize;
use std::path::Path;

#[derive(Deserialize)]
struct YamlLaser {
    laser_id: usize,
    #[serde(default)]
    rot_correction: f64,
    vert_correction: f64,
    #[serde(default)]
    dist_correction: f64,
    #[serde(default)]
    vert_offset_correction: f64,
    #[serde(default)]
    horiz_offset_correction: f64,
    #[serde(default)]
    dist_correction_x: f64,
    #[serde(default)]
    dist_correction_y: f64,
}

/// The two near-point offsets when both are set (velodyne-decoder's
/// `two_pt_correction_available`).
fn near(x: f64, y: f64) -> Option<[f64; 2]> {
    (x != 0.0 && y != 0.0).then_some([x, y])
}

#[derive(Deserialize)]
struct YamlCalibration {
    lasers: Vec<YamlLaser>,
    distance_resolution: Option<f64>,
}

fn assemble(mut lasers: Vec<(usize, Laser)>, resolution: f64) -> Result<Calibration> {
    lasers.sort_by_key(|&(id, _)| id);
    if lasers.iter().enumerate().any(|(i, &(id, _))| i != id) {
        bail!("laser ids are not 0..{} each once", lasers.len());
    }
    let lasers: Vec<Laser> = lasers.into_iter().map(|(_, l)| l).collect();
    let lasers = kiss_odom_sensors::heapless::Vec::from_slice(&lasers)
        .map_err(|_| anyhow!("{} lasers, above {MAX_LASERS}", lasers.len()))?;
    let c = Calibration {
        lasers,
        distance_resolution_m: resolution,
    };
    c.validate().map_err(|e| anyhow!("{e}"))?;
    Ok(c)
}

/// Parses a ROS `velodyne_pointcloud` YAML calibration (`distance_resolution` defaults to
/// 2 mm, as in the ROS driver).
pub fn parse_yaml(text: &str) -> Result<Calibration> {
    let y: YamlCalibration =
        serde_yaml_ng::from_str(text).context("not a Velodyne YAML calibration")?;
    let lasers = y
        .lasers
        .into_iter()
        .map(|l| {
            let laser = Laser {
                vertical_deg: l.vert_correction.to_degrees(),
                azimuth_offset_deg: -l.rot_correction.to_degrees(),
                distance_offset_m: l.dist_correction,
                vertical_offset_m: l.vert_offset_correction,
                horizontal_offset_m: l.horiz_offset_correction,
                near_distance_offset_m: near(l.dist_correction_x, l.dist_correction_y),
            };
            (l.laser_id, laser)
        })
        .collect();
    assemble(lasers, y.distance_resolution.unwrap_or(0.002))
}

/// Parses a VeloView XML calibration (`<px>` entries with `id_`, `rotCorrection_`,
/// `vertCorrection_`, `distCorrection_`, `vertOffsetCorrection_`, `horizOffsetCorrection_`;
/// `distLSB_` in cm if present, else 2 mm).
pub fn parse_xml(text: &str) -> Result<Calibration> {
    let doc = roxmltree::Document::parse(text).context("not XML")?;
    let num = |node: roxmltree::Node<'_, '_>, tag: &str| -> Result<Option<f64>> {
        match node.children().find(|c| c.has_tag_name(tag)) {
            None => Ok(None),
            Some(c) => {
                let t = c.text().unwrap_or("").trim();
                t.parse()
                    .map(Some)
                    .map_err(|_| anyhow!("{tag} is not a number: {t:?}"))
            }
        }
    };
    let mut lasers = Vec::new();
    for px in doc.descendants().filter(|n| n.has_tag_name("px")) {
        let id = num(px, "id_")?.ok_or_else(|| anyhow!("a <px> without id_"))?;
        let cm = |tag| num(px, tag).map(|v| v.unwrap_or(0.0) * 0.01);
        let laser = Laser {
            vertical_deg: num(px, "vertCorrection_")?
                .ok_or_else(|| anyhow!("laser {id} without vertCorrection_"))?,
            azimuth_offset_deg: -num(px, "rotCorrection_")?.unwrap_or(0.0),
            distance_offset_m: cm("distCorrection_")?,
            vertical_offset_m: cm("vertOffsetCorrection_")?,
            horizontal_offset_m: cm("horizOffsetCorrection_")?,
            near_distance_offset_m: near(cm("distCorrectionX_")?, cm("distCorrectionY_")?),
        };
        lasers.push((id as usize, laser));
    }
    if lasers.is_empty() {
        bail!("no <px> laser entries");
    }
    let lsb = doc
        .descendants()
        .find(|n| n.has_tag_name("distLSB_"))
        .and_then(|n| n.text()?.trim().parse::<f64>().ok())
        .map(|cm| cm * 0.01);
    assemble(lasers, lsb.unwrap_or(0.002))
}

/// Reads a calibration file, XML if it starts with `<`, YAML otherwise; errors name the file.
pub fn read(path: &Path) -> Result<Calibration> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    let parsed = if text.trim_start().starts_with('<') {
        parse_xml(&text)
    } else {
        parse_yaml(&text)
    };
    parsed.with_context(|| format!("{}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use kiss_odom_sensors::velodyne::Model;

    #[test]
    fn yaml_and_xml_of_the_same_sensor_agree_with_the_manual() {
        let nominal = Calibration::nominal(Model::Vlp32c);
        let mut yaml = String::from("distance_resolution: 0.004\nlasers:\n");
        let mut xml = String::from("<boost_serialization><DB><distLSB_>0.4</distLSB_><points_>");
        for (i, l) in nominal.lasers.iter().enumerate() {
            yaml += &format!(
                "  - {{laser_id: {i}, rot_correction: {}, vert_correction: {}}}\n",
                -l.azimuth_offset_deg.to_radians(),
                l.vertical_deg.to_radians()
            );
            xml += &format!(
                "<item><px><id_>{i}</id_><rotCorrection_>{}</rotCorrection_>\
                 <vertCorrection_>{}</vertCorrection_><distCorrection_>0</distCorrection_>\
                 </px></item>",
                -l.azimuth_offset_deg, l.vertical_deg
            );
        }
        xml += "</points_></DB></boost_serialization>";
        for c in [parse_yaml(&yaml).unwrap(), parse_xml(&xml).unwrap()] {
            assert_eq!(c.lasers.len(), 32);
            assert!((c.distance_resolution_m - 0.004).abs() < 1e-15);
            for (a, b) in c.lasers.iter().zip(&nominal.lasers) {
                assert!((a.vertical_deg - b.vertical_deg).abs() < 1e-12);
                assert!((a.azimuth_offset_deg - b.azimuth_offset_deg).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn bad_files_are_refused_with_the_reason() {
        let e = parse_yaml("lasers:\n  - {laser_id: 0, vert_correction: 0.1}\n").unwrap_err();
        assert!(format!("{e:#}").contains("calibration"), "{e:#}");
        let e = parse_xml("<DB><px><id_>0</id_><vertCorrection_>x</vertCorrection_></px></DB>")
            .unwrap_err();
        assert!(format!("{e:#}").contains("vertCorrection_"), "{e:#}");
        assert!(parse_xml("<DB></DB>").is_err());
    }
}
