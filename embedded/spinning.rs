//! Build-script part for the `velodyne` and `robosense` features: a generated Velodyne VLP-32A/B,
//! HDL-64E or VLS-128, or Robosense, recording (the model `KISS_EMBED_MODEL` names, as
//! `kiss-odom simulate --sensor` names it), and the unit's angles `simulate` wrote with it, as
//! constants in `frames.rs`: the Velodyne calibration YAML beside the pcap (`packets.yaml`) as
//! `LASERS`, or the Robosense DIFOP packet of the pcap (port 7788) as `DIFOP` (the RS-M1's and
//! E1R's points carry their directions: `SOLID_MODEL` and the `robosense_solid` cfg).

use std::fmt::Write as _;
use std::path::Path;

/// The UDP port a Robosense sensor sends its DIFOP (device information) packets to.
pub const DIFOP_PORT: u16 = 7788;

/// Which family the build embeds, and the model `KISS_EMBED_MODEL` names.
pub enum Family {
    Velodyne(String),
    Robosense(String),
}

impl Family {
    /// From the enabled features; `None` when neither `velodyne` nor `robosense` is on.
    pub fn from_features() -> Option<Self> {
        println!("cargo:rerun-if-env-changed=KISS_EMBED_MODEL");
        let model = || {
            std::env::var("KISS_EMBED_MODEL").expect("KISS_EMBED_MODEL: the model (run.sh sets it)")
        };
        if std::env::var_os("CARGO_FEATURE_VELODYNE").is_some() {
            Some(Self::Velodyne(model()))
        } else if std::env::var_os("CARGO_FEATURE_ROBOSENSE").is_some() {
            Some(Self::Robosense(model()))
        } else {
            None
        }
    }

    /// The UDP payload length of the model's data packets.
    pub fn payload(&self) -> usize {
        match self {
            Self::Velodyne(_) => 1206,
            // `kiss_odom_sensors::robosense::solid::{M1_LEN, E1R_LEN}`: their MSOP packets.
            Self::Robosense(m) if m == "m1" => 1210,
            Self::Robosense(m) if m == "e1r" => 1200,
            Self::Robosense(_) => 1248,
        }
    }

    /// The model's name as `simulate` spells it.
    pub fn name(&self) -> &str {
        match self {
            Self::Velodyne(m) | Self::Robosense(m) => m,
        }
    }

    /// The constants `stream.rs` builds the decoder from; `difop` is the recording's first
    /// DIFOP payload (Robosense).
    pub fn constants(&self, dir: &Path, difop: Option<&[u8]>) -> String {
        match self {
            Self::Velodyne(m) => velodyne(dir, m),
            Self::Robosense(m) => robosense(m, difop),
        }
    }
}

/// The Velodyne model and the calibration YAML's lasers: `[vertical_deg, azimuth_offset_deg,
/// vertical_offset_m, horizontal_offset_m]` each (the YAML's radians in degrees, its
/// `rot_correction` with the sign flipped, as `kiss-odom-io` reads it).
fn velodyne(dir: &Path, model: &str) -> String {
    let name = match model {
        "vlp32ab" => "Vlp32ab",
        "hdl64e-s2" => "Hdl64eS2",
        "hdl64e-s3" => "Hdl64eS3",
        "vls128" => "Vls128",
        m => panic!("KISS_EMBED_MODEL={m}: not a Velodyne model whose calibration simulate writes"),
    };
    let path = dir.join("packets.yaml");
    println!("cargo:rerun-if-changed={}", path.display());
    let yaml = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let field = |line: &str, key: &str| -> f64 {
        let at = line
            .find(&format!("{key}: "))
            .unwrap_or_else(|| panic!("{key} in {line}"));
        let rest = &line[at + key.len() + 2..];
        let end = rest.find([',', '}']).unwrap_or(rest.len());
        rest[..end].trim().parse().unwrap()
    };
    let resolution = yaml
        .lines()
        .find_map(|l| l.strip_prefix("distance_resolution: "))
        .map(|v| v.trim().parse::<f64>().unwrap())
        .expect("distance_resolution in packets.yaml");
    let lasers: Vec<String> = yaml
        .lines()
        .filter(|l| l.contains("laser_id"))
        .map(|l| {
            format!(
                "[{:?}, {:?}, {:?}, {:?}]",
                field(l, "vert_correction").to_degrees(),
                -field(l, "rot_correction").to_degrees(),
                field(l, "vert_offset_correction"),
                field(l, "horiz_offset_correction"),
            )
        })
        .collect();
    let mut rs = String::new();
    writeln!(
        rs,
        "/// The Velodyne model of the packets.\n\
         pub const VELODYNE_MODEL: kiss_odom_sensors::velodyne::Model = \
         kiss_odom_sensors::velodyne::Model::{name};\n\
         /// Metres a distance unit.\n\
         pub const DISTANCE_RESOLUTION_M: f64 = {resolution:?};\n\
         /// The generated unit's lasers: elevation and azimuth offset (degrees), vertical and\n\
         /// horizontal offsets (metres).\n\
         pub const LASERS: [[f64; 4]; {}] = [{}];",
        lasers.len(),
        lasers.join(", ")
    )
    .unwrap();
    rs
}

/// The Robosense model and the recording's DIFOP packet, from which the decoder takes the
/// lasers' angles.
fn robosense(model: &str, difop: Option<&[u8]>) -> String {
    if let Some(name) = [("m1", "M1"), ("e1r", "E1r")]
        .iter()
        .find_map(|(m, name)| (*m == model).then_some(name))
    {
        println!("cargo:rustc-cfg=robosense_solid");
        return format!(
            "/// The Robosense model whose returns carry their directions.\n\
             pub const SOLID_MODEL: kiss_odom_sensors::robosense::solid::Model = \
             kiss_odom_sensors::robosense::solid::Model::{name};\n"
        );
    }
    let name = match model {
        "rs16" => "Rs16",
        "rs32" => "Rs32",
        "bpearl" => "Bpearl",
        "helios" => "Helios",
        "helios16p" => "Helios16p",
        "ruby" => "Ruby",
        "airy" => "Airy",
        m => panic!("KISS_EMBED_MODEL={m}: not a Robosense model the simulator writes"),
    };
    let difop = difop.expect("no DIFOP packet (port 7788) in the Robosense pcap");
    let bytes: Vec<String> = difop.iter().map(u8::to_string).collect();
    let mut rs = String::new();
    writeln!(
        rs,
        "/// The Robosense model of the packets.\n\
         pub const ROBOSENSE_MODEL: kiss_odom_sensors::robosense::Model = \
         kiss_odom_sensors::robosense::Model::{name};\n\
         /// The recording's DIFOP packet: the lasers' angles.\n\
         pub static DIFOP: [u8; {}] = [{}];",
        bytes.len(),
        bytes.join(", ")
    )
    .unwrap();
    rs
}
