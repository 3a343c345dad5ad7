//! Welding a mesh's positions by exact equality, for [`super::adjacency`]: `-0.0` and `0.0` are one
//! position, and nothing is moved.

use std::sync::atomic::{AtomicU32, Ordering};

use glam::Vec3;
use rayon::prelude::*;

/// Bit pattern of a position with `-0.0` folded into `0.0`, so the two weld.
fn weld_key(p: Vec3) -> [u32; 3] {
    [p.x, p.y, p.z].map(|c| if c == 0.0 { 0 } else { c.to_bits() })
}

/// A hash of a weld key: multiply-rotate mixing, whose high bits are well spread (positions are not
/// adversarial, and this is many times faster than SipHash).
fn weld_hash(key: [u32; 3]) -> u64 {
    key.iter().fold(0u64, |h, &c| (h.rotate_left(26) ^ u64::from(c)).wrapping_mul(0x9e37_79b9_7f4a_7c15))
}

/// Welds equal positions (by [`weld_key`]): the distinct positions in order of first appearance, and each
/// position's index among them.
///
/// One hash table over half a million positions misses the cache on nearly every insert. So the
/// positions are first split by their hash's top byte into [`WELD_PARTS`] parts (counting sorts that
/// keep each part in position order); each part, a few thousand keys whose table stays in cache, is
/// welded on its own and in parallel, giving every position the first position with its key; a prefix
/// count over those firsts then numbers them in order of first appearance, as one table in position
/// order would. Every step runs on all threads.
pub(super) fn weld(positions: &[Vec3]) -> (Vec<Vec3>, Vec<u32>) {
    if positions.len() <= WELD_ALONE { weld_alone(positions) } else { weld_in_parts(positions) }
}

/// [`weld`] in parts, on all threads.
fn weld_in_parts(positions: &[Vec3]) -> (Vec<Vec3>, Vec<u32>) {
    let n = positions.len();
    // Each run of positions sorts its own into the parts (with its keys, so a part's table reads its
    // keys in order, not from all over the positions), all runs at once; a part's members are then its
    // members from each run, run after run: in position order.
    let per_run = n.div_ceil(rayon::current_num_threads().clamp(1, 64)).max(1);
    let runs: Vec<(Vec<usize>, Vec<[u32; 4]>)> = positions
        .par_chunks(per_run)
        .enumerate()
        .map(|(r, run)| {
            // Hashing twice costs less than keeping every key and its part between the two passes.
            let part = |k: [u32; 3]| (weld_hash(k) >> 56) as usize;
            let mut start = vec![0usize; WELD_PARTS + 1];
            for &p in run {
                start[part(weld_key(p)) + 1] += 1;
            }
            for i in 1..start.len() {
                start[i] += start[i - 1];
            }
            let mut next = start.clone();
            let mut members = vec![[0u32; 4]; run.len()];
            for (j, &p) in run.iter().enumerate() {
                let [x, y, z] = weld_key(p);
                let slot = &mut next[part([x, y, z])];
                members[*slot] = [x, y, z, (r * per_run + j) as u32];
                *slot += 1;
            }
            (start, members)
        })
        .collect();
    // Relaxed atomic stores are plain stores here; they let the parts share the array.
    let first: Vec<AtomicU32> = (0..n).into_par_iter().map(|_| AtomicU32::new(0)).collect();
    (0..WELD_PARTS).into_par_iter().for_each(|part| {
        let members = || runs.iter().flat_map(|(start, members)| &members[start[part]..start[part + 1]]);
        weld_part(members(), members().count(), &first);
    });
    let first: Vec<u32> = first.into_iter().map(AtomicU32::into_inner).collect();
    // Number the first positions in order, run by run: each run counts its firsts, then numbers its own
    // from the count of the runs before it and writes their positions. Every other position takes its
    // first's number.
    const RUN: usize = 16384;
    let is_first = |k: usize, j: usize, f: u32| f as usize == k * RUN + j;
    let counts: Vec<usize> = first
        .par_chunks(RUN)
        .enumerate()
        .map(|(k, run)| run.iter().enumerate().filter(|&(j, &f)| is_first(k, j, f)).count())
        .collect();
    let mut number = vec![0u32; n];
    let mut welded = vec![Vec3::ZERO; counts.iter().sum()];
    let mut numbering = Vec::with_capacity(counts.len());
    let (mut rest, mut at) = (welded.as_mut_slice(), 0);
    for (k, (&count, (number, first))) in counts.iter().zip(number.chunks_mut(RUN).zip(first.chunks(RUN))).enumerate() {
        let (welded, tail) = rest.split_at_mut(count);
        numbering.push((k, at, number, first, welded));
        (rest, at) = (tail, at + count);
    }
    numbering.into_par_iter().for_each(|(k, at, number, first, welded)| {
        let mut next = 0;
        for (j, (number, &f)) in number.iter_mut().zip(first).enumerate() {
            if is_first(k, j, f) {
                *number = (at + next) as u32;
                welded[next] = positions[k * RUN + j];
                next += 1;
            }
        }
    });
    let remap = first.par_iter().map(|&f| number[f as usize]).collect();
    (welded, remap)
}

/// [`weld`] of a few positions, on this thread: one table, in position order, numbering each new key as
/// it comes (the parts and the threads cost more than they save on a small mesh, and a scene of many
/// small meshes pays that cost per mesh).
fn weld_alone(positions: &[Vec3]) -> (Vec<Vec3>, Vec<u32>) {
    let (mut welded, mut remap) = (Vec::new(), Vec::new());
    weld_alone_into(positions, &mut WeldTable::default(), &mut welded, &mut remap);
    (welded, remap)
}

/// [`weld_alone`], appending the welded positions to `welded` and each position's number among them to
/// `remap`, with `table` reused from mesh to mesh (a batch of small meshes allocates it once).
pub(super) fn weld_alone_into(positions: &[Vec3], table: &mut WeldTable, welded: &mut Vec<Vec3>, remap: &mut Vec<u32>) {
    table.clear(positions.len());
    let first = welded.len();
    remap.extend(positions.iter().map(|&p| {
        let key = weld_key(p);
        let number = table.get_or_insert(key, weld_hash(key), (welded.len() - first) as u32);
        if number as usize == welded.len() - first {
            welded.push(p);
        }
        number
    }));
}

/// The most positions [`weld`] welds on one thread, in one table that stays in the cache.
pub(super) const WELD_ALONE: usize = 4096;

/// For each of one part's `count` members (`[key, position]`, in position order), the first position with
/// the same key, stored at the member's position in `first`.
fn weld_part<'a>(members: impl Iterator<Item = &'a [u32; 4]>, count: usize, first: &[AtomicU32]) {
    let mut table = WeldTable::with_room(count);
    for &[x, y, z, i] in members {
        // The bits below the part's: the top ones chose the part, so they are the same for all.
        let f = table.get_or_insert([x, y, z], weld_hash([x, y, z]) >> 24, i);
        first[i as usize].store(f, Ordering::Relaxed);
    }
}

/// Weld keys with a value each (a first position, or a number): an open addressing table with linear
/// probing, at most half full, holding each key beside its value so a probe reads no other memory.
#[derive(Default)]
pub(super) struct WeldTable {
    slots: Vec<[u32; 4]>,
}

impl WeldTable {
    const EMPTY: u32 = u32::MAX;

    /// A table for up to `count` keys.
    fn with_room(count: usize) -> Self {
        let mut table = Self::default();
        table.clear(count);
        table
    }

    /// Empties the table and makes room for `count` keys, keeping its allocation where that is enough.
    fn clear(&mut self, count: usize) {
        self.slots.clear();
        self.slots.resize((2 * count).next_power_of_two().max(16), [0, 0, 0, Self::EMPTY]);
    }

    /// The value `key` holds, or else `value`, stored for it; the probe starts at `hash`'s low bits.
    fn get_or_insert(&mut self, [x, y, z]: [u32; 3], hash: u64, value: u32) -> u32 {
        let mask = self.slots.len() - 1;
        let mut slot = hash as usize & mask;
        loop {
            match self.slots[slot] {
                [_, _, _, Self::EMPTY] => {
                    self.slots[slot] = [x, y, z, value];
                    return value;
                }
                [a, b, c, held] if [a, b, c] == [x, y, z] => return held,
                _ => slot = (slot + 1) & mask,
            }
        }
    }
}

/// How many parts [`weld`] splits the positions into: one per value of the hash's top byte.
const WELD_PARTS: usize = 256;

#[cfg(test)]
mod tests {
    use super::*;

    /// Alone and in parts, the same welding: random positions drawn from a few, with `-0.0` among them.
    #[test]
    fn welding_alone_is_welding_in_parts() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move |k: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % k) as f32
        };
        for (count, distinct) in [(0, 1), (1, 1), (7, 3), (3000, 500), (4096, 4000), (20_000, 900)] {
            let positions: Vec<Vec3> = (0..count)
                .map(|_| Vec3::new(next(distinct) - 1.0, if next(2) == 0.0 { 0.0 } else { -0.0 }, next(3) * 0.5))
                .collect();
            let (alone, in_parts) = (weld_alone(&positions), weld_in_parts(&positions));
            assert_eq!(alone.1, in_parts.1, "{count} positions");
            let bits = |w: &[Vec3]| w.iter().map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
            assert_eq!(bits(&alone.0), bits(&in_parts.0), "{count} positions");
            assert!(alone.0.len() < count.max(1) || count < 8, "{count} positions: nothing welded");
        }
    }
}
