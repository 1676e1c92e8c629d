//! Carving typed buffers out of the caller's arena of `u64` words.
//!
//! The arena is `u64` so every region starts 8-byte aligned; regions are viewed as typed slices
//! through `bytemuck`'s checked casts, so no `unsafe` is needed here.

use crate::error::ConfigError;
use bytemuck::Pod;

/// The part of the caller's arena not yet handed out.
pub struct Arena<'a> {
    rest: &'a mut [u64],
    used: usize,
}

impl<'a> Arena<'a> {
    /// Wraps the caller's words.
    pub fn new(words: &'a mut [u64]) -> Self {
        Self {
            rest: words,
            used: 0,
        }
    }

    /// Words handed out so far.
    pub fn used_words(&self) -> usize {
        self.used
    }

    /// The next `n` words.
    pub fn words(&mut self, n: usize) -> Result<&'a mut [u64], ConfigError> {
        if n > self.rest.len() {
            return Err(ConfigError::ArenaTooSmall);
        }
        let rest = core::mem::take(&mut self.rest);
        let (head, tail) = rest.split_at_mut(n);
        self.rest = tail;
        self.used += n;
        Ok(head)
    }

    /// The next `words` words viewed as `len` values of `U`, zeroed.
    pub fn slice<U: Pod>(&mut self, words: usize, len: usize) -> Result<&'a mut [U], ConfigError> {
        let w = self.words(words)?;
        w.fill(0);
        view(w, len)
    }
}

/// Views the first `len` values of type `U` in `words` (which must be long enough).
pub fn view<U: Pod>(words: &mut [u64], len: usize) -> Result<&mut [U], ConfigError> {
    let bytes: &mut [u8] = bytemuck::cast_slice_mut(words);
    let n = len
        .checked_mul(core::mem::size_of::<U>())
        .ok_or(ConfigError::ArenaTooSmall)?;
    let bytes = bytes.get_mut(..n).ok_or(ConfigError::ArenaTooSmall)?;
    bytemuck::try_cast_slice_mut(bytes).map_err(|_| ConfigError::ArenaTooSmall)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_do_not_overlap_and_short_arenas_are_refused() {
        let mut words = [0u64; 10];
        let mut arena = Arena::new(&mut words);
        let a: &mut [[f64; 3]] = arena.slice(6, 2).unwrap();
        let b: &mut [u32] = arena.slice(2, 3).unwrap();
        a[1][2] = 7.0;
        b[2] = 9;
        assert_eq!(arena.used_words(), 8);
        assert_eq!(
            arena.slice::<u8>(3, 1).err(),
            Some(ConfigError::ArenaTooSmall)
        );
        assert_eq!(a[1][2], 7.0);
        assert_eq!(b[2], 9);
    }
}
