//! Hash tables keyed by a frame's own numbers (addresses, slots, versions), for tables with one entry
//! per instance: std's SipHash resists keys chosen to collide, which these are not, at a cost a scene of
//! a hundred thousand instances feels.

use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hash, Hasher};

/// Mixes each word in with a rotation and a multiplication by 2^64 / phi; [`Hasher::finish`] folds the
/// high half into the low, as the multiplication spreads bits upwards only and a table picks its bucket
/// by the low bits (an address's low bits are zero).
#[derive(Clone, Copy, Debug, Default)]
pub struct WordHasher(u64);

impl Hasher for WordHasher {
    fn finish(&self) -> u64 {
        self.0 ^ self.0 >> 29
    }

    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }

    fn write_u64(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(26) ^ word).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }

    fn write_u32(&mut self, word: u32) {
        self.write_u64(u64::from(word));
    }

    fn write_usize(&mut self, word: usize) {
        self.write_u64(word as u64);
    }
}

/// A digest of `items` for a cache key: runs of them hashed side by side, each item by `each` into the
/// run's [`WordHasher`] (given its index), then the runs' digests in order, after `head`'s, by SipHash.
/// Every step of the word hash maps its state one to one, so a change to any one word an item hashes (a
/// caster moved, say) always changes its run's digest.
pub fn digest<T: Sync>(head: u64, items: &[T], each: impl Fn(usize, &T, &mut WordHasher) + Sync) -> u64 {
    use rayon::prelude::*;
    const RUN: usize = 1024;
    let runs: Vec<u64> = items
        .par_chunks(RUN)
        .enumerate()
        .map(|(r, run)| {
            let mut h = WordHasher::default();
            for (i, item) in run.iter().enumerate() {
                each(r * RUN + i, item, &mut h);
            }
            h.finish()
        })
        .collect();
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (head, runs).hash(&mut h);
    h.finish()
}

/// A `HashMap` hashed by [`WordHasher`].
pub type WordMap<K, V> = HashMap<K, V, BuildHasherDefault<WordHasher>>;

/// A `HashSet` hashed by [`WordHasher`].
pub type WordSet<K> = HashSet<K, BuildHasherDefault<WordHasher>>;

#[cfg(test)]
mod tests {
    use super::*;

    /// Addresses 16 bytes apart (the low four bits zero) fill a table's buckets evenly: no bucket of a
    /// 4096-bucket table holds more than a few of 4096 of them.
    #[test]
    fn aligned_addresses_spread_over_the_buckets() {
        let mut buckets = vec![0u32; 4096];
        for k in 0..4096usize {
            let mut h = WordHasher::default();
            h.write_usize(0x7f3a_0000_1000 + 16 * k);
            buckets[(h.finish() & 4095) as usize] += 1;
        }
        let fullest = buckets.iter().max().copied().unwrap_or_default();
        assert!(fullest <= 8, "a bucket holds {fullest} of 4096");
    }
}
