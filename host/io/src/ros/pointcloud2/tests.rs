//! Tests of `pointcloud2`.

use super::*;

fn field(name: &str, offset: u32, datatype: u8) -> PointField {
    PointField {
        name: name.into(),
        offset,
        datatype,
        count: 1,
    }
}

fn cloud<'a>(
    fields: Vec<PointField>,
    point_step: u32,
    width: u32,
    data: &'a [u8],
) -> PointCloud2<'a> {
    PointCloud2 {
        stamp: Stamp { sec: 5, nsec: 7 },
        frame_id: "os".into(),
        height: 1,
        width,
        fields,
        is_bigendian: false,
        point_step,
        row_step: point_step * width,
        data,
        is_dense: true,
    }
}

/// Ouster-like layout: x y z f32, intensity f32, t u32 at 16, ring u16 at 20; step 24.
fn ouster_bytes(points: &[([f32; 3], u32)], big: bool) -> Vec<u8> {
    let mut out = Vec::new();
    for (p, t) in points {
        let mut rec = [0u8; 24];
        for (k, v) in p.iter().enumerate() {
            let b = if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            };
            rec[4 * k..4 * k + 4].copy_from_slice(&b);
        }
        let tb = if big {
            t.to_be_bytes()
        } else {
            t.to_le_bytes()
        };
        rec[16..20].copy_from_slice(&tb);
        rec[20..22].copy_from_slice(&7u16.to_le_bytes());
        out.extend_from_slice(&rec);
    }
    out
}

fn ouster_fields() -> Vec<PointField> {
    vec![
        field("x", 0, FLOAT32),
        field("y", 4, FLOAT32),
        field("z", 8, FLOAT32),
        field("intensity", 12, FLOAT32),
        field("t", 16, UINT32),
        field("ring", 20, UINT16),
    ]
}

#[test]
fn reads_xyz_and_integer_time_field_in_both_byte_orders() {
    let pts = [
        ([1.5, -2.0, 0.25], 100u32),
        ([f32::NAN, 3.0, 4.0], 4_000_000_000),
    ];
    for big in [false, true] {
        let data = ouster_bytes(&pts, big);
        let mut c = cloud(ouster_fields(), 24, 2, &data);
        c.is_bigendian = big;
        let d = decode(&c).unwrap();
        assert_eq!(d.points[0], [1.5, -2.0, 0.25]);
        assert!(d.points[1][0].is_nan(), "NaN points are passed through");
        assert_eq!(d.points[1][1..], [3.0, 4.0]);
        assert_eq!(d.stamps, Some(vec![100.0, 4e9]));
        assert!(d.warnings.is_empty());
    }
}

#[test]
fn time_field_is_the_first_matching_name_in_field_order() {
    // `time` comes before `t` in the field list, so it wins, as in the reference.
    let mut data = Vec::new();
    for v in [1.0f64, 2.0, 3.0, 10.0, 20.0] {
        data.extend_from_slice(&v.to_le_bytes());
    }
    let fields = vec![
        field("x", 0, FLOAT64),
        field("y", 8, FLOAT64),
        field("z", 16, FLOAT64),
        field("time", 24, FLOAT64),
        field("t", 32, FLOAT64),
    ];
    let d = decode(&cloud(fields, 40, 1, &data)).unwrap();
    assert_eq!(d.points, vec![[1.0, 2.0, 3.0]]);
    assert_eq!(d.stamps, Some(vec![10.0]));
}

#[test]
fn cloud_without_time_field_has_no_stamps() {
    let data = ouster_bytes(&[([1.0, 2.0, 3.0], 9)], false);
    let mut fields = ouster_fields();
    fields.retain(|f| f.name != "t");
    let d = decode(&cloud(fields, 24, 1, &data)).unwrap();
    assert_eq!(d.points, vec![[1.0, 2.0, 3.0]]);
    assert_eq!(d.stamps, None);
}

#[test]
fn organized_cloud_rows_are_row_step_apart() {
    // 2 x 2 points of 12 bytes, rows padded to 28 bytes.
    let mut data = vec![0xAAu8; 56];
    for r in 0..2 {
        for c in 0..2 {
            for k in 0..3 {
                let v = (10 * r + c) as f32 + k as f32 / 4.0;
                let at = r * 28 + c * 12 + 4 * k;
                data[at..at + 4].copy_from_slice(&v.to_le_bytes());
            }
        }
    }
    let fields = vec![
        field("x", 0, FLOAT32),
        field("y", 4, FLOAT32),
        field("z", 8, FLOAT32),
    ];
    let mut c = cloud(fields, 12, 2, &data);
    c.height = 2;
    c.row_step = 28;
    let d = decode(&c).unwrap();
    assert_eq!(
        d.points,
        vec![
            [0.0, 0.25, 0.5],
            [1.0, 1.25, 1.5],
            [10.0, 10.25, 10.5],
            [11.0, 11.25, 11.5]
        ]
    );
}

#[test]
fn empty_cloud_gives_no_points() {
    let d = decode(&cloud(ouster_fields(), 24, 0, &[])).unwrap();
    assert!(d.points.is_empty());
    assert_eq!(d.stamps, Some(vec![]));
}

#[test]
fn malformed_layouts_are_errors_not_panics() {
    let data = ouster_bytes(&[([1.0, 2.0, 3.0], 1), ([4.0, 5.0, 6.0], 2)], false);
    let case = |mutate: &dyn Fn(&mut PointCloud2<'_>), needle: &str| {
        let mut c = cloud(ouster_fields(), 24, 2, &data);
        mutate(&mut c);
        let err = decode(&c).expect_err(needle);
        assert!(err.contains(needle), "{err:?} should mention {needle:?}");
    };
    case(&|c| c.point_step = 16, "does not fit in point_step");
    case(&|c| c.fields[4].offset = 22, "does not fit in point_step");
    case(&|c| c.fields[5].datatype = 9, "unknown datatype 9");
    case(&|c| c.fields[5].count = 0, "count 0");
    case(
        &|c| c.fields[3].name = "x".into(),
        "duplicate field name `x`",
    );
    case(&|c| c.fields.remove(1).name.clear(), "no field `y`");
    case(
        &|c| c.fields[0].datatype = INT32,
        "must be FLOAT32 or FLOAT64",
    );
    case(&|c| c.fields[2].count = 2, "field `z` has count 2");
    case(&|c| c.fields[4].count = 2, "time field `t` has count 2");
    case(&|c| c.row_step = 47, "row_step 47 is less than");
    case(
        &|c| {
            c.width = 3;
            c.row_step = 72;
        },
        "needs 72",
    );
    // A count-2 field `n` provides `n_0` and `n_1`, so a field `n_1` collides (`n_2` would not).
    let subfield = |c: &mut PointCloud2<'_>, other: &str| {
        c.fields[3].name = "n".into();
        c.fields[3].count = 2;
        c.fields[5].name = other.into();
    };
    case(&|c| subfield(c, "n_1"), "duplicate field name `n_1`");
    let mut c = cloud(ouster_fields(), 24, 2, &data);
    subfield(&mut c, "n_2");
    assert!(decode(&c).is_ok());
    case(&|c| c.height = u32::MAX, "needs");
    case(&|c| c.data = &c.data[..47], "needs 48");
}

#[test]
fn extra_bytes_after_the_last_row_are_a_warning() {
    let mut data = ouster_bytes(&[([1.0, 2.0, 3.0], 1)], false);
    data.extend_from_slice(&[0, 0, 0]);
    let d = decode(&cloud(ouster_fields(), 24, 1, &data)).unwrap();
    assert_eq!(d.points.len(), 1);
    assert_eq!(
        d.warnings,
        vec!["3 bytes after the last row ignored".to_string()]
    );
}

#[test]
fn topic_choice_follows_the_reference_rules() {
    let topics = |v: &[(&str, &str)]| -> Vec<(String, String)> {
        v.iter()
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .collect()
    };
    let pc = |t: &str| t == "PC2";
    let one = topics(&[("/points", "PC2"), ("/imu", "Imu")]);
    assert_eq!(
        choose_topic("f", &one, pc, Wanted::cloud("PC2"), None).unwrap(),
        "/points"
    );
    let two = topics(&[("/b", "PC2"), ("/a", "PC2"), ("/imu", "Imu")]);
    let e = choose_topic("f", &two, pc, Wanted::cloud("PC2"), None).unwrap_err();
    assert!(
        e.contains("several") && e.contains("/a, /b") && e.contains("--topic"),
        "{e}"
    );
    assert_eq!(
        choose_topic("f", &two, pc, Wanted::cloud("PC2"), Some("/b")).unwrap(),
        "/b"
    );
    let e = choose_topic("f", &two, pc, Wanted::cloud("PC2"), Some("/imu")).unwrap_err();
    assert!(e.contains("/imu carries Imu"), "{e}");
    let e = choose_topic("f", &two, pc, Wanted::cloud("PC2"), Some("/nope")).unwrap_err();
    assert!(e.contains("no topic /nope"), "{e}");
    let e = choose_topic(
        "f",
        &topics(&[("/imu", "Imu")]),
        pc,
        Wanted::cloud("PC2"),
        None,
    )
    .unwrap_err();
    assert!(
        e.contains("no PC2 topic") && e.contains("/imu (Imu)"),
        "{e}"
    );
}

#[test]
fn a_cloud_ends_at_its_latest_point_time_unless_those_are_offsets() {
    let header = 1_700_000_000.25;
    // Seconds on the header's clock: the driver takes the latest of them.
    assert_eq!(
        sweep_end(header, Some(&[header - 0.1, header - 0.001])),
        None
    );
    // Offsets from the sweep's start (Ouster's `t` in ns, Velodyne's `time` in s): the header.
    assert_eq!(sweep_end(header, Some(&[0.0, 99_000_000.0])), Some(header));
    assert_eq!(sweep_end(header, Some(&[-0.1, 0.0])), Some(header));
    assert_eq!(sweep_end(header, None), None);
    assert_eq!(sweep_end(header, Some(&[])), None);
}
