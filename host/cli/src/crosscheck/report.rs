//! The cross-check's table: one row per figure, the tolerance next to it, and the verdict.
//!
//! A row is either a check (a measured figure against an allowed bound: PASS or FAIL) or a
//! report (a figure the issue asks to see without a bound, such as throughput). The exit status
//! is 1 when any check fails, and every breach is named on stderr.

use anyhow::Result;
use serde::Serialize;
use std::io::Write;

/// How a row ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Outcome {
    /// Within tolerance.
    Pass,
    /// Tolerance exceeded (or the figure could not be computed).
    Fail,
    /// A reported figure without a tolerance.
    Report,
}

/// One line of the table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    /// What was compared.
    pub check: String,
    /// The measured figure, with its unit.
    pub measured: String,
    /// The tolerance, or `report`.
    pub allowed: String,
    /// The verdict.
    pub outcome: Outcome,
    /// The figure compared against `limit`, for machine readers.
    pub value: Option<f64>,
    /// The bound, for machine readers.
    pub limit: Option<f64>,
}

/// A figure as `1.23e-11`, or `0` for an exact zero.
pub fn sci(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v:.2e}")
    }
}

impl Row {
    /// `value <= limit` (a NaN value fails), with free texts for the two columns.
    pub fn check(
        check: impl Into<String>,
        value: f64,
        limit: f64,
        measured: String,
        allowed: String,
    ) -> Self {
        Self {
            check: check.into(),
            measured,
            allowed,
            outcome: if value <= limit {
                Outcome::Pass
            } else {
                Outcome::Fail
            },
            value: Some(value),
            limit: Some(limit),
        }
    }

    /// `value <= limit`, both printed with `unit`.
    pub fn bound(check: impl Into<String>, value: f64, limit: f64, unit: &str) -> Self {
        let with_unit = |v: f64| format!("{} {unit}", sci(v)).trim_end().to_string();
        Self::check(
            check,
            value,
            limit,
            with_unit(value),
            format!("<= {}", with_unit(limit)),
        )
    }

    /// `differ` items of `of` disagree; none may.
    pub fn none_differ(check: impl Into<String>, differ: usize, of: usize, what: &str) -> Self {
        Self {
            check: check.into(),
            measured: format!("{differ} of {of} {what} differ"),
            allowed: "0 differ".into(),
            outcome: if differ == 0 {
                Outcome::Pass
            } else {
                Outcome::Fail
            },
            value: Some(differ as f64),
            limit: Some(0.0),
        }
    }

    /// A check that could not be evaluated (e.g. different point counts): a failure.
    pub fn broken(check: impl Into<String>, measured: String, allowed: &str) -> Self {
        Self {
            check: check.into(),
            measured,
            allowed: allowed.into(),
            outcome: Outcome::Fail,
            value: None,
            limit: None,
        }
    }

    /// A reported figure.
    pub fn report(check: impl Into<String>, measured: String) -> Self {
        Self {
            check: check.into(),
            measured,
            allowed: "report".into(),
            outcome: Outcome::Report,
            value: None,
            limit: None,
        }
    }
}

/// Rows under one heading.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Section {
    /// Heading.
    pub title: String,
    /// Rows in order.
    pub rows: Vec<Row>,
}

impl Section {
    /// An empty section.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            rows: Vec::new(),
        }
    }
    /// Appends a row.
    pub fn push(&mut self, row: Row) {
        self.rows.push(row);
    }
}

/// How the table is printed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum TableStyle {
    /// Aligned columns for a terminal.
    Text,
    /// A Markdown table per section (for BENCHMARKS.md).
    Markdown,
}

/// The whole cross-check: a title, notes (dataset, versions, command) and sections.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Report {
    /// One line naming the dataset and the run.
    pub title: String,
    /// Lines printed under the title.
    pub notes: Vec<String>,
    /// Sections in order.
    pub sections: Vec<Section>,
}

impl Report {
    /// Every failed check as `section: check: measured (allowed ...)`.
    pub fn breaches(&self) -> Vec<String> {
        self.sections
            .iter()
            .flat_map(|s| {
                s.rows
                    .iter()
                    .filter(|r| r.outcome == Outcome::Fail)
                    .map(move |r| {
                        format!(
                            "{}: {}: {} (allowed {})",
                            s.title, r.check, r.measured, r.allowed
                        )
                    })
            })
            .collect()
    }

    /// Number of checks (rows with a tolerance).
    pub fn checks(&self) -> usize {
        self.sections
            .iter()
            .flat_map(|s| &s.rows)
            .filter(|r| r.outcome != Outcome::Report)
            .count()
    }

    /// Prints the table.
    pub fn write_table(&self, out: &mut dyn Write, style: TableStyle) -> Result<()> {
        match style {
            TableStyle::Text => {
                writeln!(out, "{}", self.title)?;
                for n in &self.notes {
                    writeln!(out, "  {n}")?;
                }
            }
            TableStyle::Markdown => {
                writeln!(out, "**{}**\n", self.title)?;
                for n in &self.notes {
                    writeln!(out, "- {n}")?;
                }
            }
        }
        for s in &self.sections {
            writeln!(out)?;
            match style {
                TableStyle::Text => write_text_section(out, s)?,
                TableStyle::Markdown => write_markdown_section(out, s)?,
            }
        }
        Ok(())
    }

    /// Names every breach on `err` and returns the exit status: 1 on any breach, else 0.
    pub fn verdict(&self, err: &mut dyn Write) -> i32 {
        let breaches = self.breaches();
        if breaches.is_empty() {
            let _ = writeln!(
                err,
                "crosscheck: all {} checks within tolerance",
                self.checks()
            );
            return 0;
        }
        for b in &breaches {
            let _ = writeln!(err, "FAIL: {b}");
        }
        let _ = writeln!(
            err,
            "crosscheck: {} of {} checks exceed their tolerance",
            breaches.len(),
            self.checks()
        );
        1
    }
}

fn result_word(o: Outcome) -> &'static str {
    match o {
        Outcome::Pass => "PASS",
        Outcome::Fail => "FAIL",
        Outcome::Report => "-",
    }
}

fn write_text_section(out: &mut dyn Write, s: &Section) -> Result<()> {
    writeln!(out, "{}", s.title)?;
    let head = ["check", "measured", "allowed", "result"];
    let cells: Vec<[&str; 4]> = s
        .rows
        .iter()
        .map(|r| {
            [
                r.check.as_str(),
                r.measured.as_str(),
                r.allowed.as_str(),
                result_word(r.outcome),
            ]
        })
        .collect();
    let mut w = head.map(str::len);
    for c in &cells {
        for i in 0..4 {
            w[i] = w[i].max(c[i].chars().count());
        }
    }
    let line = |c: [&str; 4]| {
        format!(
            "  {:<w0$}  {:<w1$}  {:<w2$}  {}",
            c[0],
            c[1],
            c[2],
            c[3],
            w0 = w[0],
            w1 = w[1],
            w2 = w[2]
        )
    };
    writeln!(out, "{}", line(head).trim_end())?;
    for c in cells {
        writeln!(out, "{}", line(c).trim_end())?;
    }
    Ok(())
}

fn write_markdown_section(out: &mut dyn Write, s: &Section) -> Result<()> {
    writeln!(out, "*{}*\n", s.title)?;
    writeln!(out, "| check | measured | allowed | result |")?;
    writeln!(out, "|---|---|---|---|")?;
    let esc = |t: &str| t.replace('|', "\\|");
    for r in &s.rows {
        writeln!(
            out,
            "| {} | {} | {} | {} |",
            esc(&r.check),
            esc(&r.measured),
            esc(&r.allowed),
            result_word(r.outcome)
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report_with(rows: Vec<Row>) -> Report {
        Report {
            title: "t".into(),
            notes: vec![],
            sections: vec![Section {
                title: "stages".into(),
                rows,
            }],
        }
    }

    #[test]
    fn a_breach_exits_1_and_is_named() {
        let r = report_with(vec![
            Row::bound("deskew", 1e-12, 1e-9, "m"),
            Row::bound("registration translation", 2e-6, 1e-6, "m"),
            Row::report("throughput", "10 Hz".into()),
        ]);
        let mut err = Vec::new();
        assert_eq!(r.verdict(&mut err), 1);
        let err = String::from_utf8(err).unwrap();
        assert!(
            err.contains(
                "FAIL: stages: registration translation: 2.00e-6 m (allowed <= 1.00e-6 m)"
            ),
            "{err}"
        );
        assert!(!err.contains("deskew"), "{err}");
        assert!(err.contains("1 of 2 checks"), "{err}");
    }

    #[test]
    fn all_within_tolerance_exits_0() {
        let r = report_with(vec![
            Row::bound("crop", 0.0, 1e-9, "m"),
            Row::none_differ("downsampling set", 0, 5000, "points"),
            Row::report("order", "identical".into()),
        ]);
        let mut err = Vec::new();
        assert_eq!(r.verdict(&mut err), 0);
        assert_eq!(r.checks(), 2);
    }

    #[test]
    fn nan_counts_and_broken_checks_fail() {
        assert_eq!(Row::bound("x", f64::NAN, 1.0, "m").outcome, Outcome::Fail);
        assert_eq!(
            Row::none_differ("pairs", 1, 10, "pairs").outcome,
            Outcome::Fail
        );
        assert_eq!(
            Row::broken("crop", "10 vs 11 points".into(), "same points").outcome,
            Outcome::Fail
        );
        // The bound itself passes.
        assert_eq!(Row::bound("x", 0.01, 0.01, "m").outcome, Outcome::Pass);
    }

    #[test]
    fn tables_put_the_tolerance_next_to_each_figure() {
        let r = report_with(vec![Row::bound("deskew", 3e-15, 1e-9, "m")]);
        let mut text = Vec::new();
        r.write_table(&mut text, TableStyle::Text).unwrap();
        let text = String::from_utf8(text).unwrap();
        let line = text.lines().find(|l| l.contains("deskew")).unwrap();
        assert!(
            line.contains("3.00e-15 m") && line.contains("<= 1.00e-9 m") && line.contains("PASS")
        );
        let mut md = Vec::new();
        r.write_table(&mut md, TableStyle::Markdown).unwrap();
        let md = String::from_utf8(md).unwrap();
        assert!(
            md.contains("| deskew | 3.00e-15 m | <= 1.00e-9 m | PASS |"),
            "{md}"
        );
    }
}
