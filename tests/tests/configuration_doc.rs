//! The book's configuration reference (`docs/configuration.md`) lists every settings key in its
//! section, no key that does not exist, and an `accurate` value exactly where that preset
//! changes the key.

use kiss_odom_drive::settings::{Caps, Input, PresetName, Settings};
use serde_json::Value;
use std::collections::BTreeMap;

/// Section -> key -> the row's cells, from the chapter's `## `[section]`` tables.
fn documented() -> BTreeMap<String, BTreeMap<String, Vec<String>>> {
    let text = std::fs::read_to_string(kiss_odom_tests::repo().join("docs/configuration.md"))
        .expect("docs/configuration.md");
    let mut out: BTreeMap<String, BTreeMap<String, Vec<String>>> = BTreeMap::new();
    let mut section = None;
    let mut header: Vec<String> = Vec::new();
    for line in text.lines() {
        if let Some(h) = line.strip_prefix("## `[") {
            section = h.split(']').next().map(str::to_string);
            header.clear();
            continue;
        }
        if line.starts_with("## ") {
            section = None;
            continue;
        }
        let (Some(s), true) = (&section, line.starts_with('|')) else {
            continue;
        };
        let cells: Vec<String> = line
            .trim_matches('|')
            .split('|')
            .map(|c| c.trim().into())
            .collect();
        if header.is_empty() {
            header = cells;
            continue;
        }
        let Some(key) = cells[0].strip_prefix('`').and_then(|k| k.strip_suffix('`')) else {
            continue; // the |---| line
        };
        let mut row = Vec::new();
        for (h, c) in header.iter().zip(&cells) {
            row.push(format!("{h}={c}"));
        }
        out.entry(s.clone()).or_default().insert(key.into(), row);
    }
    out
}

/// Section -> key -> value of the settings, with every optional key given.
fn keys(preset: PresetName) -> BTreeMap<String, BTreeMap<String, Value>> {
    let mut s = Settings::preset(preset);
    s.mapping.voxel_size.get_or_insert(1.0);
    s.registration.kernel_scale.get_or_insert(1.0);
    s.registration.work_budget.get_or_insert(1);
    s.runtime.memory_limit.get_or_insert(1);
    s.capacities = Caps::from(kiss_odom_core::Capacities::SMALL);
    s.imu.enabled = true; // left out of the file while off
                          // [input] and [output] are left out while at their defaults, and so are absent keys.
    s.input = Input {
        port: Some(1),
        cut_angle: Some(0.0),
        frame_period: Some(0.1),
    };
    s.output.strict = true;
    let v = serde_json::to_value(&s).expect("settings serialize");
    let mut out = BTreeMap::new();
    for (section, table) in v.as_object().expect("sections") {
        let table = table.as_object().expect("keys");
        let keys = table.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
        out.insert(section.clone(), keys);
    }
    out
}

#[test]
fn every_settings_key_is_in_the_reference_and_every_row_is_a_key() {
    let doc = documented();
    let have = keys(PresetName::Default);
    let mut missing = Vec::new();
    for (section, table) in &have {
        for key in table.keys() {
            if !doc.get(section).is_some_and(|d| d.contains_key(key)) {
                missing.push(format!("[{section}] {key}"));
            }
        }
    }
    let mut stale = Vec::new();
    for (section, table) in &doc {
        for key in table.keys() {
            if !have.get(section).is_some_and(|h| h.contains_key(key)) {
                stale.push(format!("[{section}] {key}"));
            }
        }
    }
    println!(
        "{} sections, {} keys documented",
        doc.len(),
        doc.values().map(|t| t.len()).sum::<usize>()
    );
    assert!(
        missing.is_empty(),
        "settings not in docs/configuration.md: {missing:?}"
    );
    assert!(
        stale.is_empty(),
        "docs/configuration.md rows that are no setting: {stale:?}"
    );
}

#[test]
fn the_accurate_column_is_filled_exactly_where_the_preset_changes_a_key() {
    let doc = documented();
    let (default, accurate) = (keys(PresetName::Default), keys(PresetName::Accurate));
    let mut wrong = Vec::new();
    let mut changed = 0;
    for (section, table) in &default {
        for (key, value) in table {
            if key == "voxel_size" || key == "preset" {
                continue; // follows the range in both presets; the preset's own name
            }
            let differs = accurate[section][key] != *value;
            changed += usize::from(differs);
            let Some(row) = doc.get(section).and_then(|d| d.get(key)) else {
                continue; // the other test names it
            };
            let cell = row.iter().find_map(|c| c.strip_prefix("accurate="));
            let filled = cell.is_some_and(|c| !c.is_empty());
            if filled != differs {
                wrong.push(format!(
                    "[{section}] {key}: preset changes it: {differs}, cell {cell:?}"
                ));
            }
        }
    }
    println!("{changed} keys the accurate preset changes");
    assert!(changed > 0, "the accurate preset changes nothing?");
    assert!(wrong.is_empty(), "{wrong:#?}");
}
