//! PLY scans through `ply-rs`: the `vertex` element's `x`, `y`, `z` and, if present, a per-point
//! time field (see [`STAMP_FIELDS`]), any scalar type, ascii or binary of either endianness.
//!
//! Vertices are decoded into a small fixed struct rather than `ply-rs`'s per-point hash map, so
//! a 100k-point scan costs one allocation per property name, not one map per point.

use super::file_cloud::{Cloud, STAMP_FIELDS};
use anyhow::{anyhow, bail, Context, Result};
use ply_rs::parser::Parser;
use ply_rs::ply::{
    Addable, ElementDef, Encoding, Header, Property, PropertyAccess, PropertyDef, PropertyType,
    ScalarType,
};
use ply_rs::writer::Writer;
use std::collections::HashSet;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, Write};
use std::path::Path;

/// Name of the time property the writers use.
const WRITTEN_STAMP_FIELD: &str = "time";

/// One vertex: coordinates and every candidate time field (which one is used depends on the
/// header, which `PropertyAccess::new` does not see).
#[derive(Clone, Copy, Debug, Default)]
struct Vertex {
    xyz: [f64; 3],
    stamps: [f64; STAMP_FIELDS.len()],
}

fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v.into(),
        Property::UChar(v) => v.into(),
        Property::Short(v) => v.into(),
        Property::UShort(v) => v.into(),
        Property::Int(v) => v.into(),
        Property::UInt(v) => v.into(),
        Property::Float(v) => v.into(),
        Property::Double(v) => v,
        _ => return None,
    })
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: String, property: Property) {
        let Some(v) = scalar(&property) else { return };
        match name.as_str() {
            "x" => self.xyz[0] = v,
            "y" => self.xyz[1] = v,
            "z" => self.xyz[2] = v,
            other => {
                if let Some(i) = STAMP_FIELDS.iter().position(|f| *f == other) {
                    self.stamps[i] = v;
                }
            }
        }
    }

    fn get_double(&self, name: &String) -> Option<f64> {
        match name.as_str() {
            "x" => Some(self.xyz[0]),
            "y" => Some(self.xyz[1]),
            "z" => Some(self.xyz[2]),
            other => STAMP_FIELDS
                .iter()
                .position(|f| *f == other)
                .map(|i| self.stamps[i]),
        }
    }
}

fn is_scalar(element: &ElementDef, name: &str) -> bool {
    element
        .properties
        .get(name)
        .is_some_and(|p| matches!(p.data_type, PropertyType::Scalar(_)))
}

/// `ply-rs` errors span several lines and end with the parser's list of expected tokens; keep
/// the first line's worth.
fn flat(e: std::io::Error) -> anyhow::Error {
    let mut text = e
        .to_string()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    if let Some(end) = text.find(" Error: ParseError") {
        text.truncate(end);
    }
    anyhow!(text)
}

/// Bytes of the file the header check looks at; a longer header is garbage.
const HEADER_BYTES: u64 = 64 * 1024;

/// Checks what `ply-rs` trusts: it unwraps every number of the header as a u64 (a longer one
/// panics, found by fuzzing), sizes element lists from their declared counts, and keeps one
/// property per name (a second `x` would silently change the stride it reads with). A header
/// whose numbers do not fit, whose elements could not fit in the `file_len`-byte file (every
/// item takes at least one byte), or that declares a property twice is refused here.
fn check_header(head: &[u8], file_len: u64) -> Result<()> {
    let text = String::from_utf8_lossy(head);
    let mut items: u64 = 0;
    let mut element = String::new();
    let mut names: HashSet<String> = HashSet::new();
    for line in text.lines().take_while(|l| l.trim() != "end_header") {
        let words: Vec<&str> = line.split_whitespace().collect();
        // Every run of digits, also inside a word: the grammar reads them wherever they are.
        for run in line.split(|c: char| !c.is_ascii_digit()) {
            if !run.is_empty() && run.parse::<u64>().is_err() {
                bail!("PLY header number {run} is too large");
            }
        }
        match words[..] {
            ["element", name, count] => {
                if let Ok(n) = count.parse::<u64>() {
                    items = items.saturating_add(n);
                }
                element = name.to_string();
                names.clear();
            }
            ["property", .., name] if !names.insert(name.to_string()) => {
                bail!("PLY element {element} declares property {name} twice");
            }
            _ => {}
        }
    }
    if items > file_len {
        bail!("PLY header declares {items} items, more than a {file_len}-byte file holds");
    }
    Ok(())
}

/// Reads the whole scan at `path`.
pub fn read(path: &Path) -> Result<Cloud> {
    read_at_most(path, usize::MAX)
}

/// Reads at most the first `max_points` vertices of the scan at `path`; the rest of the file
/// is not read.
pub fn read_at_most(path: &Path, max_points: usize) -> Result<Cloud> {
    let mut file = File::open(path)?;
    let file_len = file.metadata()?.len();
    let mut head = Vec::new();
    (&mut file).take(HEADER_BYTES).read_to_end(&mut head)?;
    check_header(&head, file_len)?;
    drop(head);
    file.rewind()?;
    let mut reader = BufReader::new(file);
    let parser = Parser::<Vertex>::new();
    let header = parser
        .read_header(&mut reader)
        .map_err(flat)
        .context("not a PLY header")?;
    let Some(vertex) = header.elements.get("vertex") else {
        bail!("PLY has no vertex element");
    };
    if let Some(axis) = ["x", "y", "z"].into_iter().find(|a| !is_scalar(vertex, a)) {
        bail!("PLY vertex element has no scalar property {axis}");
    }
    let stamp = STAMP_FIELDS.iter().position(|f| is_scalar(vertex, f));

    // Elements are stored one after the other; those before `vertex` are read and dropped, and
    // only the first `max_points` vertices are read.
    for (name, element) in &header.elements {
        let mut element = element.clone();
        let declared = element.count;
        if name == "vertex" {
            element.count = declared.min(max_points);
        }
        let items = parser
            .read_payload_for_element(&mut reader, &element, &header)
            .map_err(flat)
            .with_context(|| format!("PLY {name} data truncated or malformed"))?;
        if name == "vertex" {
            return Ok(Cloud {
                points: items.iter().map(|v| v.xyz).collect(),
                stamps: stamp.map(|i| items.iter().map(|v| v.stamps[i]).collect()),
                declared,
            });
        }
    }
    bail!("PLY has no vertex element")
}

/// Writes `points` (and `stamps` as a `time` property) as binary little-endian PLY with
/// `double` properties, so that every `f64` reads back exactly.
pub fn write(path: &Path, points: &[[f64; 3]], stamps: Option<&[f64]>) -> Result<()> {
    write_with(path, points, stamps, Encoding::BinaryLittleEndian)
}

/// Like [`write()`], ascii (shortest round-trip decimals).
pub fn write_ascii(path: &Path, points: &[[f64; 3]], stamps: Option<&[f64]>) -> Result<()> {
    write_with(path, points, stamps, Encoding::Ascii)
}

fn write_with(
    path: &Path,
    points: &[[f64; 3]],
    stamps: Option<&[f64]>,
    encoding: Encoding,
) -> Result<()> {
    let stamp_index = STAMP_FIELDS
        .iter()
        .position(|f| *f == WRITTEN_STAMP_FIELD)
        .ok_or_else(|| anyhow!("{WRITTEN_STAMP_FIELD} is not a time field"))?;
    if let Some(s) = stamps {
        if s.len() != points.len() {
            bail!("{} stamps for {} points", s.len(), points.len());
        }
    }
    let mut element = ElementDef::new("vertex".to_string());
    element.count = points.len();
    let double = || PropertyType::Scalar(ScalarType::Double);
    for name in ["x", "y", "z"] {
        element
            .properties
            .add(PropertyDef::new(name.into(), double()));
    }
    if stamps.is_some() {
        let def = PropertyDef::new(WRITTEN_STAMP_FIELD.into(), double());
        element.properties.add(def);
    }
    let mut header = Header::new();
    header.encoding = encoding;
    header.elements.add(element.clone());

    let write = || -> std::io::Result<()> {
        let mut out = BufWriter::new(File::create(path)?);
        let writer = Writer::<Vertex>::new();
        writer.write_header(&mut out, &header)?;
        for (i, p) in points.iter().enumerate() {
            let mut v = Vertex {
                xyz: *p,
                ..Vertex::default()
            };
            if let Some(s) = stamps {
                v.stamps[stamp_index] = s[i];
            }
            match encoding {
                Encoding::Ascii => writer.write_ascii_element(&mut out, &v, &element)?,
                Encoding::BinaryLittleEndian => {
                    writer.write_little_endian_element(&mut out, &v, &element)?
                }
                Encoding::BinaryBigEndian => {
                    writer.write_big_endian_element(&mut out, &v, &element)?
                }
            };
        }
        out.flush()
    };
    write().with_context(|| format!("{}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_declares_doubles_and_time() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.ply");
        write(&path, &[[1.0, 2.0, 3.0]], Some(&[0.5])).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        for line in [
            "format binary_little_endian 1.0",
            "element vertex 1",
            "property double x",
            "property double time",
            "end_header",
        ] {
            assert!(text.contains(line), "missing {line:?} in {text}");
        }
        // Header, then 4 doubles.
        let end = text.find("end_header\n").unwrap() + "end_header\n".len();
        assert_eq!(bytes.len() - end, 32);
        assert_eq!(bytes[end + 8..end + 16], 2.0f64.to_le_bytes());
    }

    #[test]
    fn properties_of_any_scalar_type_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.ply");
        let text = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n\
                    property int y\nproperty uchar z\nproperty ushort t\nend_header\n\
                    0.5 -3 7 65535\n1 2 255 0\n";
        std::fs::write(&path, text).unwrap();
        let cloud = read(&path).unwrap();
        assert_eq!(cloud.points, vec![[0.5, -3.0, 7.0], [1.0, 2.0, 255.0]]);
        assert_eq!(cloud.stamps, Some(vec![65535.0, 0.0]));
    }

    #[test]
    fn stamp_field_priority_follows_the_reference() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.ply");
        // `time` comes first in the file, but the reference looks up `t` before `time`.
        let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\n\
                    property double y\nproperty double z\nproperty double time\n\
                    property double t\nend_header\n1 2 3 10 20\n";
        std::fs::write(&path, text).unwrap();
        assert_eq!(read(&path).unwrap().stamps, Some(vec![20.0]));
    }

    #[test]
    fn a_property_declared_twice_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.ply");
        let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n\
                    property float x\nproperty float y\nproperty float z\nend_header\n1 2 3 4\n";
        std::fs::write(&path, text).unwrap();
        let e = format!("{:#}", read(&path).unwrap_err());
        assert!(e.contains("property x twice"), "{e}");
    }

    #[test]
    fn only_the_first_max_points_vertices_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.ply");
        let points: Vec<[f64; 3]> = (0..5).map(|i| [f64::from(i), 1.0, 2.0]).collect();
        for ascii in [false, true] {
            if ascii {
                write_ascii(&path, &points, None).unwrap();
            } else {
                write(&path, &points, None).unwrap();
            }
            let cloud = read_at_most(&path, 3).unwrap();
            assert_eq!(cloud.points, points[..3]);
            assert_eq!(cloud.declared, 5);
        }
    }

    #[test]
    fn missing_coordinate_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.ply");
        let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\n\
                    property double y\nend_header\n1 2\n";
        std::fs::write(&path, text).unwrap();
        let e = format!("{:#}", read(&path).unwrap_err());
        assert!(e.contains("property z"), "{e}");
    }
}
