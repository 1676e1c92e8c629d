//! PCD scans through `pcd-rs`: fields `x`, `y`, `z` and, if present, a per-point time field
//! (see [`STAMP_FIELDS`]), any numeric type, `DATA ascii` or `DATA binary`.
//!
//! `pcd-rs` 0.12 does not decode `DATA binary_compressed`; such files are reported as skipped
//! frames with that reason rather than parsed by hand.

use super::file_cloud::{Cloud, STAMP_FIELDS};
use anyhow::{anyhow, bail, Context, Result};
use pcd_rs::{DataKind, DynReader, DynRecord, DynWriter, Field, Schema, ValueKind, WriterInit};
use std::io::{Cursor, Read};
use std::path::Path;

/// Name of the time field the writers use.
const WRITTEN_STAMP_FIELD: &str = "time";

/// Largest total `COUNT` accepted: beyond this a header is garbage (and `pcd-rs` would add the
/// counts up without overflow checks).
const MAX_VALUES_PER_POINT: u64 = 1 << 16;

/// The first value of a field as `f64`.
fn value(field: &Field) -> Option<f64> {
    match field {
        Field::I8(v) => v.first().map(|&x| x.into()),
        Field::I16(v) => v.first().map(|&x| x.into()),
        Field::I32(v) => v.first().map(|&x| x.into()),
        Field::U8(v) => v.first().map(|&x| x.into()),
        Field::U16(v) => v.first().map(|&x| x.into()),
        Field::U32(v) => v.first().map(|&x| x.into()),
        Field::F32(v) => v.first().map(|&x| x.into()),
        Field::F64(v) => v.first().copied(),
    }
}

/// Says what is wrong with a header `pcd-rs` rejected when it is a known unsupported variant.
fn explain_header_error(path: &Path, e: pcd_rs::Error) -> anyhow::Error {
    let mut head = Vec::new();
    let compressed = std::fs::File::open(path)
        .and_then(|f| f.take(4096).read_to_end(&mut head))
        .is_ok()
        && String::from_utf8_lossy(&head)
            .lines()
            .any(|l| l.split_whitespace().eq(["DATA", "binary_compressed"]));
    if compressed {
        anyhow!("PCD DATA binary_compressed is not supported (pcd-rs 0.12)")
    } else {
        // The message already includes its source; `{:#}` would repeat it.
        anyhow!(e.to_string()).context("not a PCD header")
    }
}

/// Reads the whole scan at `path`.
pub fn read(path: &Path) -> Result<Cloud> {
    read_at_most(path, usize::MAX)
}

/// Reads at most the first `max_points` points of the scan at `path` (`pcd-rs` reads records
/// one at a time, so the rest of the file is not read).
pub fn read_at_most(path: &Path, max_points: usize) -> Result<Cloud> {
    let reader = DynReader::open(path).map_err(|e| explain_header_error(path, e))?;
    let meta = reader.meta().clone();
    let fields = &meta.field_defs;
    let total: u64 = fields
        .iter()
        .fold(0u64, |acc, f| acc.saturating_add(f.count));
    if total > MAX_VALUES_PER_POINT {
        bail!("PCD header declares {total} values per point");
    }
    let index_of = |name: &str| fields.iter().position(|f| f.name == name && f.count == 1);
    let mut xyz = [0; 3];
    for (slot, axis) in xyz.iter_mut().zip(["x", "y", "z"]) {
        *slot = index_of(axis).ok_or_else(|| anyhow!("PCD has no single-valued field {axis}"))?;
    }
    let stamp = STAMP_FIELDS.iter().find_map(|f| index_of(f));

    let declared = usize::try_from(meta.num_points).unwrap_or(usize::MAX);
    let n = declared.min(max_points);
    // The header's count is not trusted for allocation; the data decides.
    let mut points = Vec::with_capacity(n.min(1 << 20));
    let mut stamps = stamp.map(|_| Vec::with_capacity(n.min(1 << 20)));
    for (i, record) in reader.take(n).enumerate() {
        let DynRecord(record) =
            record.map_err(|e| anyhow!("PCD point {i} of {n} truncated or malformed: {e}"))?;
        let get = |k: usize| {
            record
                .get(k)
                .and_then(value)
                .ok_or_else(|| anyhow!("PCD point {i} has no field {k}"))
        };
        points.push([get(xyz[0])?, get(xyz[1])?, get(xyz[2])?]);
        if let (Some(k), Some(s)) = (stamp, stamps.as_mut()) {
            s.push(get(k)?);
        }
    }
    if points.len() != n {
        bail!("PCD data has {} of {n} points", points.len());
    }
    Ok(Cloud {
        points,
        stamps,
        declared,
    })
}

/// Writes `points` (and `stamps` as a `time` field) as `DATA binary` PCD with `F 8` fields, so
/// that every `f64` reads back exactly.
pub fn write(path: &Path, points: &[[f64; 3]], stamps: Option<&[f64]>) -> Result<()> {
    write_with(path, points, stamps, DataKind::Binary)
}

/// Like [`write()`], `DATA ascii` (shortest round-trip decimals).
pub fn write_ascii(path: &Path, points: &[[f64; 3]], stamps: Option<&[f64]>) -> Result<()> {
    write_with(path, points, stamps, DataKind::Ascii)
}

fn write_with(
    path: &Path,
    points: &[[f64; 3]],
    stamps: Option<&[f64]>,
    data_kind: DataKind,
) -> Result<()> {
    if let Some(s) = stamps {
        if s.len() != points.len() {
            bail!("{} stamps for {} points", s.len(), points.len());
        }
    }
    let mut names = vec!["x", "y", "z"];
    if stamps.is_some() {
        names.push(WRITTEN_STAMP_FIELD);
    }
    let schema: Schema = names.iter().map(|&n| (n, ValueKind::F64, 1)).collect();

    // `pcd-rs`'s writer panics when dropped unfinished, and finishing seeks back into the
    // output; an in-memory buffer makes both infallible, the file is written in one go.
    let mut buf = Cursor::new(Vec::new());
    let mut writer: DynWriter<_> = WriterInit {
        width: points.len() as u64,
        height: 1,
        viewpoint: Default::default(),
        data_kind,
        schema: Some(schema),
    }
    .build_from_writer(&mut buf)?;
    let mut pushed = Ok(());
    for (i, p) in points.iter().enumerate() {
        let mut record: Vec<Field> = p.iter().map(|&v| Field::F64(vec![v])).collect();
        if let Some(s) = stamps {
            record.push(Field::F64(vec![s[i]]));
        }
        pushed = writer.push(&DynRecord(record));
        if pushed.is_err() {
            break;
        }
    }
    let finished = writer.finish();
    pushed?;
    finished?;
    std::fs::write(path, buf.into_inner()).with_context(|| format!("{}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_of_any_numeric_type_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.pcd");
        let text = "VERSION .7\nFIELDS x y z intensity t\nSIZE 4 8 2 4 4\nTYPE F F I F U\n\
                    COUNT 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\n\
                    DATA ascii\n0.5 -1.25 -3 9 100\n1 2 3 0 4294967295\n";
        std::fs::write(&path, text).unwrap();
        let cloud = read(&path).unwrap();
        assert_eq!(cloud.points, vec![[0.5, -1.25, -3.0], [1.0, 2.0, 3.0]]);
        assert_eq!(cloud.stamps, Some(vec![100.0, 4294967295.0]));
    }

    #[test]
    fn binary_compressed_is_reported_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.pcd");
        let text = "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\n\
                    HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA binary_compressed\n";
        std::fs::write(&path, text).unwrap();
        let e = format!("{:#}", read(&path).unwrap_err());
        assert!(e.contains("binary_compressed"), "{e}");
    }

    #[test]
    fn only_the_first_max_points_points_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.pcd");
        let points: Vec<[f64; 3]> = (0..5).map(|i| [f64::from(i), 1.0, 2.0]).collect();
        write(&path, &points, Some(&[0.0, 0.1, 0.2, 0.3, 0.4])).unwrap();
        let cloud = read_at_most(&path, 2).unwrap();
        assert_eq!(cloud.points, points[..2]);
        assert_eq!(cloud.stamps, Some(vec![0.0, 0.1]));
        assert_eq!(cloud.declared, 5);
    }

    #[test]
    fn fewer_points_than_declared_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.pcd");
        write(&path, &[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]], None).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 4]).unwrap();
        assert!(read(&path).is_err());
    }
}
