//! The items of a dataset in a frame range, in order: what `run` feeds the driver and what
//! `bench` and `crosscheck` preload.

use crate::dataset::{FrameSource, Item};
use anyhow::Result;
use std::str::FromStr;

/// A half-open range of frame indices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameRange {
    /// First frame.
    pub start: usize,
    /// One past the last frame, if bounded.
    pub end: Option<usize>,
}

impl FrameRange {
    /// Whether `i` is inside.
    pub fn contains(&self, i: usize) -> bool {
        i >= self.start && self.end.is_none_or(|e| i < e)
    }

    /// Whether every index from `i` on is past the end.
    pub fn is_past(&self, i: usize) -> bool {
        self.end.is_some_and(|e| i >= e)
    }
}

impl std::fmt::Display for FrameRange {
    /// As it is written on the command line: `3..`, `3..7`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}..", self.start)?;
        match self.end {
            Some(e) => write!(f, "{e}"),
            None => Ok(()),
        }
    }
}

impl FromStr for FrameRange {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let bad = || format!("'{s}' is not a frame range like 10..20, 10.. or ..20");
        let (a, b) = s.split_once("..").ok_or_else(bad)?;
        let start = if a.is_empty() {
            0
        } else {
            a.trim().parse().map_err(|_| bad())?
        };
        let end = if b.is_empty() {
            None
        } else {
            Some(b.trim().parse().map_err(|_| bad())?)
        };
        if end.is_some_and(|e| e <= start) {
            return Err(format!("'{s}' is empty"));
        }
        Ok(Self { start, end })
    }
}

/// The items of a source whose index is in a range. The source seeks to the range's start if
/// its format can; reading stops at the first item past the end, and after an error.
pub struct Selection<'a> {
    source: &'a mut dyn FrameSource,
    range: FrameRange,
    done: bool,
}

impl<'a> Selection<'a> {
    /// The items of `source` in `range`.
    pub fn new(source: &'a mut dyn FrameSource, range: FrameRange) -> Self {
        if range.start > 0 {
            source.seek(range.start);
        }
        Self {
            source,
            range,
            done: false,
        }
    }

    /// How many items the range will give, if the source knows its length.
    pub fn len_hint(&self) -> Option<usize> {
        self.source.len_hint().map(|n| {
            let end = self.range.end.map_or(n, |e| e.min(n));
            end.saturating_sub(self.range.start)
        })
    }
}

impl Iterator for Selection<'_> {
    type Item = Result<Item>;

    fn next(&mut self) -> Option<Result<Item>> {
        while !self.done {
            match self.source.next_item() {
                Err(e) => {
                    self.done = true;
                    return Some(Err(e));
                }
                Ok(None) => self.done = true,
                Ok(Some(item)) => {
                    let index = item.index();
                    if self.range.contains(index) {
                        return Some(Ok(item));
                    }
                    self.done = self.range.is_past(index);
                }
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_parse_print_and_reject_nonsense() {
        let r: FrameRange = "3..7".parse().unwrap();
        assert_eq!((r.start, r.end, r.to_string()), (3, Some(7), "3..7".into()));
        assert!(r.contains(3) && !r.contains(7) && r.is_past(7) && !r.is_past(6));
        let r: FrameRange = "5..".parse().unwrap();
        assert_eq!((r.start, r.end, r.to_string()), (5, None, "5..".into()));
        let r: FrameRange = "..4".parse().unwrap();
        assert_eq!((r.start, r.end), (0, Some(4)));
        assert!("7..3".parse::<FrameRange>().is_err());
        assert!("x".parse::<FrameRange>().is_err());
    }

    use crate::dataset::Frame;

    /// Frames 0..n, with `bad` unreadable and an error at `fail`; counts reads.
    struct Fake {
        next: usize,
        n: usize,
        fail: Option<usize>,
        reads: usize,
    }

    impl FrameSource for Fake {
        fn len_hint(&self) -> Option<usize> {
            Some(self.n)
        }
        fn next_item(&mut self) -> Result<Option<Item>> {
            self.reads += 1;
            let i = self.next;
            self.next += 1;
            if Some(i) == self.fail {
                anyhow::bail!("cut at {i}");
            }
            Ok((i < self.n).then(|| {
                if i == 3 {
                    Item::Skipped {
                        index: i,
                        name: format!("{i}.bin"),
                        time: None,
                        reason: "bad".into(),
                    }
                } else {
                    Item::Frame(Frame {
                        index: i,
                        ..Frame::default()
                    })
                }
            }))
        }
    }

    fn fake(n: usize, fail: Option<usize>) -> Fake {
        Fake {
            next: 0,
            n,
            fail,
            reads: 0,
        }
    }

    #[test]
    fn a_range_gives_its_items_and_stops_reading_after_its_end() {
        let mut src = fake(10, None);
        let sel = Selection::new(&mut src, "2..5".parse().unwrap());
        assert_eq!(sel.len_hint(), Some(3));
        let got: Vec<usize> = sel.map(|i| i.unwrap().index()).collect();
        assert_eq!(got, [2, 3, 4]);
        assert_eq!(src.reads, 6, "reads up to the first index past the end");
    }

    #[test]
    fn an_error_ends_the_selection_after_the_items_before_it() {
        let mut src = fake(10, Some(2));
        let got: Vec<Result<Item>> = Selection::new(&mut src, FrameRange::default()).collect();
        assert_eq!(got.len(), 3);
        assert!(got[2].is_err());
        let mut src = fake(4, None);
        assert_eq!(
            Selection::new(&mut src, "1..".parse().unwrap()).len_hint(),
            Some(3)
        );
    }
}
