//! Numeric text tables (the datasets' ground-truth CSV and TXT files) read as `np.loadtxt`
//! reads them: one row a line, lines starting with `#` and blank lines skipped, every row the
//! same number of columns; a cell that is not a number, or a ragged row, is an error naming
//! the file and line.

use anyhow::{bail, Context, Result};
use std::path::Path;

/// How cells are separated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sep {
    /// A comma.
    Comma,
    /// Any run of spaces or tabs.
    Space,
}

/// One row: its line number (1-based) and its cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Line number in the file, 1-based.
    pub line: usize,
    /// The numbers.
    pub cells: Vec<f64>,
}

/// The rows of the table at `path` (what it is: `what`, for the message when it is missing),
/// skipping the first `header` lines, each with at least `min_cols` columns.
pub fn read(path: &Path, sep: Sep, header: usize, min_cols: usize, what: &str) -> Result<Vec<Row>> {
    if !path.is_file() {
        bail!("{}: no such file ({what})", path.display());
    }
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    parse(&text, sep, header, min_cols).with_context(|| format!("{} ({what})", path.display()))
}

/// [`read`] of text already in memory; errors name the line.
pub fn parse(text: &str, sep: Sep, header: usize, min_cols: usize) -> Result<Vec<Row>> {
    let mut rows: Vec<Row> = Vec::new();
    for (i, line) in text.lines().enumerate().skip(header) {
        let trimmed = line.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        let cells: Vec<&str> = match sep {
            Sep::Comma => trimmed.split(',').map(str::trim).collect(),
            Sep::Space => trimmed.split_whitespace().collect(),
        };
        let cells = cells
            .iter()
            .map(|c| {
                c.parse::<f64>()
                    .with_context(|| format!("line {}: {c:?} is not a number", i + 1))
            })
            .collect::<Result<Vec<f64>>>()?;
        if let Some(first) = rows.first() {
            if cells.len() != first.cells.len() {
                bail!(
                    "line {}: {} columns, but line {} has {}",
                    i + 1,
                    cells.len(),
                    first.line,
                    first.cells.len()
                );
            }
        } else if cells.len() < min_cols {
            bail!(
                "line {}: {} columns, expected at least {min_cols}",
                i + 1,
                cells.len()
            );
        }
        rows.push(Row { line: i + 1, cells });
    }
    if rows.is_empty() {
        bail!("no rows");
    }
    Ok(rows)
}

/// The index of the row whose first cell is nearest to `t`, the first of equals, as
/// `np.argmin(abs(times - t))`; with how far it is.
pub fn nearest(times: &[f64], t: f64) -> Option<(usize, f64)> {
    let mut best: Option<(usize, f64)> = None;
    for (i, &s) in times.iter().enumerate() {
        let d = (s - t).abs();
        if best.is_none_or(|(_, b)| d < b) {
            best = Some((i, d));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_skip_comments_and_refuse_ragged_lines_and_words() {
        let rows = parse("# a header\n1, 2,3\n\n4,5,6\n", Sep::Comma, 0, 3).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[1].line, 4);
        assert_eq!(rows[1].cells, vec![4.0, 5.0, 6.0]);
        let e = format!("{:#}", parse("1,2,3\n4,5\n", Sep::Comma, 0, 3).unwrap_err());
        assert!(e.contains("line 2") && e.contains("2 columns"), "{e}");
        let e = format!("{:#}", parse("1 2 x\n", Sep::Space, 0, 3).unwrap_err());
        assert!(e.contains("\"x\" is not a number"), "{e}");
        assert!(parse("t,x\n1,2\n", Sep::Comma, 1, 2).is_ok());
        assert!(parse("", Sep::Comma, 0, 1).is_err());
    }

    #[test]
    fn nearest_takes_the_first_of_equals() {
        assert_eq!(nearest(&[0.0, 10.0, 20.0], 5.0), Some((0, 5.0)));
        assert_eq!(nearest(&[0.0, 10.0, 20.0], 14.0), Some((1, 4.0)));
        assert_eq!(nearest(&[], 1.0), None);
    }
}
