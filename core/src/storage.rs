//! Where the pipeline's buffers live: one run of `u64` words, owned or borrowed.
//!
//! Every buffer of the pipeline (the two downsampled clouds, the downsampling scratch, ICP's
//! work chunks, the local map) is a named [`Region`] of one run of words whose length a `const
//! fn` computes ([`crate::Capacities::arena_words`]). The words can be anything that derefs to
//! `[u64]` ([`Storage`]), smoltcp `ManagedSlice` style:
//!
//! - borrowed: `&mut [u64]` (a stack array, a slice of a `static`);
//! - owned, fixed size: [`Words<N>`], const-constructible, so firmware can keep it in a `static`
//!   (for example `static_cell::ConstStaticCell<Words<N>>`, then `take()` it once);
//! - owned, boxed: `Box<[u64]>` or `Vec<u64>` on a host, with `Odometry::boxed` behind
//!   the `alloc` feature, which a bare-metal build never enables.
//!
//! The words are `u64` so that every region starts 8-byte aligned; regions are viewed as typed
//! slices through `bytemuck`'s checked casts, so no `unsafe` is needed.

use crate::error::ConfigError;
use bytemuck::Pod;

/// Anything holding the pipeline's words: `&mut [u64]`, [`Words<N>`], `Box<[u64]>`, `Vec<u64>`.
pub trait Storage: AsRef<[u64]> + AsMut<[u64]> {}

impl<S: AsRef<[u64]> + AsMut<[u64]> + ?Sized> Storage for S {}

/// `N` words owned in place, zeroed by a `const fn`: storage that can be a `static`.
///
/// ```
/// use kiss_odom_core::{Capacities, Exact, Words};
/// const N: usize = Capacities::SMALL.arena_words::<f32, Exact>();
/// static STATE: Words<N> = Words::new(); // in firmware: a ConstStaticCell<Words<N>>
/// assert_eq!(STATE.as_ref().len(), N);
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct Words<const N: usize>([u64; N]);

impl<const N: usize> Words<N> {
    /// `N` zero words.
    pub const fn new() -> Self {
        Self([0; N])
    }
}

impl<const N: usize> Default for Words<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> AsRef<[u64]> for Words<N> {
    fn as_ref(&self) -> &[u64] {
        &self.0
    }
}

impl<const N: usize> AsMut<[u64]> for Words<N> {
    fn as_mut(&mut self) -> &mut [u64] {
        &mut self.0
    }
}

/// A run of words inside the storage: `start..start + len`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Region {
    /// First word.
    pub start: usize,
    /// Words.
    pub len: usize,
}

impl Region {
    /// One past the last word.
    pub const fn end(&self) -> usize {
        self.start + self.len
    }
}

/// Hands out consecutive regions while a layout is being computed (`const`).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Carver {
    next: usize,
}

impl Carver {
    pub(crate) const fn new() -> Self {
        Self { next: 0 }
    }

    /// The next `len` words.
    pub(crate) const fn take(&mut self, len: usize) -> Region {
        let r = Region {
            start: self.next,
            len,
        };
        self.next += len;
        r
    }

    /// Words handed out so far.
    pub(crate) const fn used(&self) -> usize {
        self.next
    }
}

/// `u64` words holding `bytes` bytes.
pub(crate) const fn words_for(bytes: usize) -> usize {
    bytes.div_ceil(8)
}

/// Splits `words` into the front `region` (which must start at `words`' start) and the rest.
pub(crate) fn split_off(
    words: &mut [u64],
    region: Region,
) -> Result<(&mut [u64], &mut [u64]), ConfigError> {
    if region.len > words.len() {
        return Err(ConfigError::ArenaTooSmall);
    }
    Ok(words.split_at_mut(region.len))
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

/// Read-only [`view`].
pub fn view_ref<U: Pod>(words: &[u64], len: usize) -> Result<&[U], ConfigError> {
    let bytes: &[u8] = bytemuck::cast_slice(words);
    let n = len
        .checked_mul(core::mem::size_of::<U>())
        .ok_or(ConfigError::ArenaTooSmall)?;
    let bytes = bytes.get(..n).ok_or(ConfigError::ArenaTooSmall)?;
    bytemuck::try_cast_slice(bytes).map_err(|_| ConfigError::ArenaTooSmall)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_are_consecutive_and_short_storage_is_refused() {
        let mut c = Carver::new();
        let a = c.take(6);
        let b = c.take(2);
        assert_eq!(
            (a.start, a.end(), b.start, b.end(), c.used()),
            (0, 6, 6, 8, 8)
        );
        let mut words = [0u64; 10];
        let (head, rest) = split_off(&mut words, a).unwrap();
        let pts: &mut [[f64; 3]] = view(head, 2).unwrap();
        pts[1][2] = 7.0;
        let (head, rest) = split_off(rest, b).unwrap();
        let ints: &mut [u32] = view(head, 3).unwrap();
        ints[2] = 9;
        assert_eq!(rest.len(), 2);
        assert_eq!(
            split_off(rest, Region { start: 8, len: 3 }).err(),
            Some(ConfigError::ArenaTooSmall)
        );
        assert_eq!(view::<u8>(rest, 17).err(), Some(ConfigError::ArenaTooSmall));
        assert_eq!(f64::from_bits(words[5]), 7.0);
    }

    #[test]
    fn words_are_zero_and_usable_as_storage() {
        fn len<S: Storage>(s: &mut S) -> usize {
            s.as_mut().len()
        }
        let mut w = Words::<5>::new();
        assert_eq!(len(&mut w), 5);
        assert!(w.as_ref().iter().all(|&x| x == 0));
        let mut arr = [1u64; 3];
        let mut borrowed: &mut [u64] = &mut arr;
        assert_eq!(len(&mut borrowed), 3);
    }
}
