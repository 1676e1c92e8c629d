//! The items of a dataset in a frame range, in order: what `run` feeds the driver and what
//! `bench` and `crosscheck` preload.

use crate::args::FrameRange;
use crate::io::{FrameSource, Item};
use anyhow::Result;

/// The frame index of an item.
pub fn index_of(item: &Item) -> usize {
    match item {
        Item::Frame(f) => f.index,
        Item::Skipped { index, .. } => *index,
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
                    let index = index_of(&item);
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
    use crate::io::Frame;

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
        let got: Vec<usize> = sel.map(|i| index_of(&i.unwrap())).collect();
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
