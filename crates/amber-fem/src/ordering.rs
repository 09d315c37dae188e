//! Fill-reducing elimination order for large stiffness matrices: nested dissection by coordinate
//! bisection, which mesh graphs suit (their unknowns know where they are).

use std::sync::atomic::{AtomicU32, Ordering};

/// Subproblems this small are eliminated in their given order (16 left the least fill on a
/// 1M-triangle mesh; docs/PROFILES.md).
const LEAF: usize = 16;

/// Subproblems below this size are dissected on the calling thread.
const PARALLEL_MIN: usize = 1 << 12;

/// An elimination order of the `points.len()` unknowns of a symmetric pattern given as
/// adjacency lists (neighbours of `v` at `adjacency[adjacency_start[v]..adjacency_start[v + 1]]`):
/// `order[k]` is eliminated k-th.
///
/// Each level splits its unknowns at the median along their widest axis (ties by index); the
/// left half's unknowns with a neighbour in the right half form the separator, eliminated after
/// both halves. The order depends on the points and the pattern only, not on the thread count.
pub(crate) fn nested_dissection<const D: usize>(
    points: &[[f64; D]],
    adjacency_start: &[u32],
    adjacency: &[u32],
) -> Vec<u32> {
    let n = points.len();
    let dissection =
        Dissection { points, adjacency_start, adjacency, right_of: (0..n).map(|_| AtomicU32::new(0)).collect() };
    let mut order: Vec<u32> = (0..n as u32).collect();
    dissection.split(&mut order, 1);
    order
}

struct Dissection<'a, const D: usize> {
    points: &'a [[f64; D]],
    adjacency_start: &'a [u32],
    adjacency: &'a [u32],
    /// The split that put the unknown on its right side (0: none). Splits are numbered as the
    /// nodes of a binary heap, so concurrent splits never share a number.
    right_of: Vec<AtomicU32>,
}

impl<const D: usize> Dissection<'_, D> {
    /// Reorders `ids` (the unknowns of split `split`) into their elimination order.
    fn split(&self, ids: &mut [u32], split: u32) {
        if ids.len() <= LEAF {
            return;
        }
        let (mut lo, mut hi) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
        for &v in ids.iter() {
            for k in 0..D {
                lo[k] = lo[k].min(self.points[v as usize][k]);
                hi[k] = hi[k].max(self.points[v as usize][k]);
            }
        }
        let axis = (0..D).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b]))).unwrap_or(0);
        let mid = ids.len() / 2;
        let points = self.points;
        ids.select_nth_unstable_by(mid, |&a, &b| {
            points[a as usize][axis].total_cmp(&points[b as usize][axis]).then(a.cmp(&b))
        });
        for &v in &ids[mid..] {
            self.right_of[v as usize].store(split, Ordering::Relaxed);
        }
        let touches_right = |v: u32| {
            let range = self.adjacency_start[v as usize] as usize..self.adjacency_start[v as usize + 1] as usize;
            self.adjacency[range].iter().any(|&w| self.right_of[w as usize].load(Ordering::Relaxed) == split)
        };
        // [left interior | separator | right] → [left interior | right | separator].
        let mut separator = Vec::new();
        let mut interior = 0;
        for i in 0..mid {
            let v = ids[i];
            if touches_right(v) {
                separator.push(v);
            } else {
                ids[interior] = v;
                interior += 1;
            }
        }
        ids.copy_within(mid.., interior);
        let right_end = interior + ids.len() - mid;
        ids[right_end..].copy_from_slice(&separator);
        let (left, rest) = ids.split_at_mut(interior);
        let right = &mut rest[..right_end - interior];
        let (left_split, right_split) = (split.wrapping_mul(2), split.wrapping_mul(2).wrapping_add(1));
        if left.len() + right.len() >= PARALLEL_MIN {
            rayon::join(|| self.split(left, left_split), || self.split(right, right_split));
        } else {
            self.split(left, left_split);
            self.split(right, right_split);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 5-point stencil's neighbours on a `k × l` grid.
    fn grid(k: usize, l: usize) -> (Vec<[f64; 2]>, Vec<u32>, Vec<u32>) {
        let points = (0..k * l).map(|v| [(v % k) as f64, (v / k) as f64]).collect();
        let (mut start, mut adjacency) = (vec![0u32], Vec::new());
        for v in 0..k * l {
            let (i, j) = (v % k, v / k);
            let steps =
                [(i > 0, v.wrapping_sub(1)), (i + 1 < k, v + 1), (j > 0, v.wrapping_sub(k)), (j + 1 < l, v + k)];
            adjacency.extend(steps.iter().filter(|s| s.0).map(|s| s.1 as u32));
            start.push(adjacency.len() as u32);
        }
        (points, start, adjacency)
    }

    #[test]
    fn separators_come_after_the_halves_they_separate() {
        let (k, l) = (40, 30);
        let (points, start, adjacency) = grid(k, l);
        let n = k * l;
        let order = nested_dissection(&points, &start, &adjacency);
        let mut seen = vec![false; n];
        for &v in &order {
            assert!(!std::mem::replace(&mut seen[v as usize], true), "{v} twice");
        }
        // The first split cuts the 40 × 30 grid across x, its widest axis, at its median: the last
        // 30 unknowns eliminated are the column x = 19, whose neighbours at x = 20 are on the right.
        let last: Vec<u32> = order[n - l..].to_vec();
        assert!(last.iter().all(|&v| points[v as usize][0] == 19.0), "{last:?}");
        // And the two halves never meet before it: every earlier pair of neighbours lies on one side.
        let position: Vec<usize> = {
            let mut p = vec![0; n];
            for (at, &v) in order.iter().enumerate() {
                p[v as usize] = at;
            }
            p
        };
        let half = |v: usize| points[v][0] < 19.0;
        for a in 0..n {
            for &b in &adjacency[start[a] as usize..start[a + 1] as usize] {
                let b = b as usize;
                if position[a] < n - l && position[b] < n - l {
                    assert_eq!(half(a), half(b), "{a} and {b} are neighbours across the separator");
                }
            }
        }
    }

    #[test]
    fn solids_are_cut_by_planes() {
        // A 20 × 12 × 8 grid of points with its 6-neighbour graph: the first cut is across x, its
        // widest axis, and its separator, eliminated last, is the plane x = 9.
        let (k, l, m) = (20, 12, 8);
        let n = k * l * m;
        let id = |i: usize, j: usize, h: usize| (h * l + j) * k + i;
        let points: Vec<[f64; 3]> =
            (0..n).map(|v| [(v % k) as f64, ((v / k) % l) as f64, (v / (k * l)) as f64]).collect();
        let (mut start, mut adjacency) = (vec![0u32], Vec::new());
        for v in 0..n {
            let (i, j, h) = (v % k, (v / k) % l, v / (k * l));
            let steps = [
                (i > 0, [i.wrapping_sub(1), j, h]),
                (i + 1 < k, [i + 1, j, h]),
                (j > 0, [i, j.wrapping_sub(1), h]),
                (j + 1 < l, [i, j + 1, h]),
                (h > 0, [i, j, h.wrapping_sub(1)]),
                (h + 1 < m, [i, j, h + 1]),
            ];
            adjacency.extend(steps.iter().filter(|s| s.0).map(|s| id(s.1[0], s.1[1], s.1[2]) as u32));
            start.push(adjacency.len() as u32);
        }
        let order = nested_dissection(&points, &start, &adjacency);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..n as u32).collect::<Vec<_>>());
        assert!(order[n - l * m..].iter().all(|&v| points[v as usize][0] == 9.0));
    }

    #[test]
    fn the_order_does_not_depend_on_the_thread_count() {
        let (points, start, adjacency) = grid(150, 120);
        let on = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| nested_dissection(&points, &start, &adjacency))
        };
        assert_eq!(on(1), on(3));
    }
}
