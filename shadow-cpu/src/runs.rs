//! Work over many items of varied sizes (a frame's instances), each writing its own stretch of one
//! output: consecutive small items go to a thread together, in runs of about a job's elements, and an
//! item larger than a job is a run of its own, which it may split among the threads itself. A frame of
//! many small meshes pays a thread's hand-off per run, not per mesh.

use std::ops::Range;

use rayon::prelude::*;

/// Where each item starts in an output of all of them, `counts[i]` elements for item `i`, and the total
/// at the end.
#[must_use]
pub fn starts(counts: &[usize]) -> Vec<usize> {
    let mut total = 0;
    std::iter::once(0)
        .chain(counts.iter().map(|&n| {
            total += n;
            total
        }))
        .collect()
}

/// Calls `each(items, stretch)` on all threads for runs of consecutive items, `stretch` the run's part
/// of `output` (laid out by `starts`, from [`starts`]): runs of about `job` elements, an item of more
/// than `job` a run of its own.
pub fn for_each_run<T: Send>(
    starts: &[usize],
    output: &mut [T],
    job: usize,
    each: impl Fn(Range<usize>, &mut [T]) + Sync,
) {
    let items = starts.len() - 1;
    let large = |i: usize| starts[i + 1] - starts[i] > job;
    let mut runs: Vec<(Range<usize>, &mut [T])> = Vec::new();
    let (mut rest, mut first) = (output, 0);
    for k in 1..=items {
        if k == items || starts[k] - starts[first] >= job || large(k) || large(k - 1) {
            let (run, tail) = std::mem::take(&mut rest).split_at_mut(starts[k] - starts[first]);
            runs.push((first..k, run));
            (rest, first) = (tail, k);
        }
    }
    runs.into_par_iter().for_each(|(items, stretch)| each(items, stretch));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every item gets its own stretch, once, whatever the mix of sizes; a large item runs alone and
    /// small ones are grouped.
    #[test]
    fn each_item_writes_its_own_stretch() {
        let counts: Vec<usize> = (0..500).map(|i| if i % 97 == 3 { 5000 } else { i % 7 }).collect();
        let starts = starts(&counts);
        assert_eq!(starts.len(), counts.len() + 1);
        let mut output = vec![usize::MAX; starts[counts.len()]];
        let runs = std::sync::Mutex::new(Vec::new());
        for_each_run(&starts, &mut output, 256, |items, stretch| {
            assert_eq!(stretch.len(), starts[items.end] - starts[items.start]);
            let mut stretch = stretch;
            for i in items.clone() {
                let (mine, tail) = std::mem::take(&mut stretch).split_at_mut(counts[i]);
                mine.fill(i);
                stretch = tail;
            }
            runs.lock().expect("no panic").push(items);
        });
        for (i, w) in starts.windows(2).enumerate() {
            assert!(output[w[0]..w[1]].iter().all(|&o| o == i), "item {i}");
        }
        let runs = runs.into_inner().expect("no panic");
        assert!(runs.iter().all(|r| r.len() == 1 || r.clone().all(|i| counts[i] <= 256)));
        assert!(runs.len() < counts.len() / 4, "{} runs of {} items", runs.len(), counts.len());
    }
}
