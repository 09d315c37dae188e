//! The replay buffer (spec §6, reference notes §6.1–6.3): one protected depth-0 entry per
//! training problem, never evicted, plus a FIFO of generated meshes; least-used-first batches up
//! to a node budget; stratified choice of the source of the next generated mesh.

use std::collections::{BTreeSet, VecDeque};

use rand::Rng;

use amber_tasks::MeshState;

use crate::SourceSelection;

/// A training graph: a mesh state with its labels and raw training targets.
#[derive(Clone, Debug)]
pub struct Sample<const D: usize> {
    pub state: MeshState<D>,
    /// The expert sizing field projected onto the mesh.
    pub labels: Vec<f64>,
    /// The un-normalised regression targets derived from the labels (see
    /// [`crate::TargetTransform::raw_targets`]).
    pub targets: Vec<f64>,
}

/// One buffer entry.
#[derive(Clone, Debug)]
pub struct BufferEntry<const D: usize> {
    /// Unique within a run, increasing in insertion order (names the entry in checkpoints).
    pub id: u64,
    /// Index of the training problem the mesh belongs to.
    pub problem: usize,
    /// Generation steps from M⁰ (protected entries: 0).
    pub depth: usize,
    /// How many batches the entry has been in.
    pub sampled_count: u64,
    pub sample: Sample<D>,
}

/// Protected entries plus a FIFO of at most `capacity` generated entries.
#[derive(Clone, Debug)]
pub struct ReplayBuffer<const D: usize> {
    protected: Vec<BufferEntry<D>>,
    online: VecDeque<BufferEntry<D>>,
    capacity: usize,
    next_id: u64,
}

impl<const D: usize> ReplayBuffer<D> {
    /// An empty buffer keeping at most `capacity` generated entries.
    pub fn new(capacity: usize) -> Self {
        Self { protected: Vec::new(), online: VecDeque::new(), capacity, next_id: 0 }
    }

    /// Adds the never-evicted depth-0 entry of `problem`.
    pub fn push_protected(&mut self, problem: usize, sample: Sample<D>) {
        let id = self.take_id();
        self.protected.push(BufferEntry { id, problem, depth: 0, sampled_count: 0, sample });
    }

    /// Adds a generated entry with the integer mean use count of all entries (so it is neither
    /// starved nor preferred), evicting the oldest generated entry when full. Returns the evicted
    /// entry.
    pub fn push_generated(&mut self, problem: usize, depth: usize, sample: Sample<D>) -> Option<BufferEntry<D>> {
        let total: u64 = self.entries().map(|e| e.sampled_count).sum();
        let sampled_count = total.checked_div(self.len() as u64).unwrap_or(0);
        let id = self.take_id();
        self.online.push_back(BufferEntry { id, problem, depth, sampled_count, sample });
        if self.online.len() > self.capacity { self.online.pop_front() } else { None }
    }

    /// Re-inserts entries restored from a checkpoint, keeping their ids and counts.
    pub(crate) fn restore(
        capacity: usize,
        next_id: u64,
        protected: Vec<BufferEntry<D>>,
        online: Vec<BufferEntry<D>>,
    ) -> Self {
        Self { protected, online: online.into(), capacity, next_id }
    }

    fn take_id(&mut self) -> u64 {
        self.next_id += 1;
        self.next_id - 1
    }

    /// The id the next entry will get.
    pub fn next_id(&self) -> u64 {
        self.next_id
    }

    /// Protected entries then generated entries, oldest first.
    pub fn entries(&self) -> impl Iterator<Item = &BufferEntry<D>> {
        self.protected.iter().chain(&self.online)
    }

    /// The protected entries.
    pub fn protected(&self) -> &[BufferEntry<D>] {
        &self.protected
    }

    /// The generated entries, oldest first.
    pub fn generated(&self) -> impl Iterator<Item = &BufferEntry<D>> {
        self.online.iter()
    }

    /// All entries.
    pub fn len(&self) -> usize {
        self.protected.len() + self.online.len()
    }

    /// Whether the buffer holds no entry at all.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The entry at position `index` of [`Self::entries`].
    pub fn get(&self, index: usize) -> &BufferEntry<D> {
        match index.checked_sub(self.protected.len()) {
            None => &self.protected[index],
            Some(i) => &self.online[i],
        }
    }

    fn get_mut(&mut self, index: usize) -> &mut BufferEntry<D> {
        match index.checked_sub(self.protected.len()) {
            None => &mut self.protected[index],
            Some(i) => &mut self.online[i],
        }
    }

    /// Number of entries of each depth (index = depth).
    pub fn depth_histogram(&self) -> Vec<usize> {
        let mut histogram = Vec::new();
        for e in self.entries() {
            if histogram.len() <= e.depth {
                histogram.resize(e.depth + 1, 0);
            }
            histogram[e.depth] += 1;
        }
        histogram
    }

    /// Chooses the source of the next generated entry among entries of depth ≤ `max_depth`:
    /// stratified (a depth uniformly among those present, then an entry of it uniformly) or
    /// uniform over the entries. Returns its position in [`Self::entries`].
    pub fn choose_source<R: Rng + ?Sized>(
        &self,
        max_depth: usize,
        selection: SourceSelection,
        rng: &mut R,
    ) -> Option<usize> {
        let allowed: Vec<usize> = (0..self.len()).filter(|&i| self.get(i).depth <= max_depth).collect();
        if allowed.is_empty() {
            return None;
        }
        let pool = match selection {
            SourceSelection::Uniform => allowed,
            SourceSelection::Stratified => {
                let depths: Vec<usize> =
                    allowed.iter().map(|&i| self.get(i).depth).collect::<BTreeSet<_>>().into_iter().collect();
                let depth = depths[rng.random_range(0..depths.len())];
                allowed.into_iter().filter(|&i| self.get(i).depth == depth).collect()
            }
        };
        Some(pool[rng.random_range(0..pool.len())])
    }

    /// The next batch: entries in increasing order of use count (ties: buffer order), taken
    /// while the node total stays within `node_budget` and stopping at the first that does not
    /// fit (a single entry larger than the budget forms a batch alone). Increments the use
    /// count of every chosen entry and returns their positions.
    pub fn next_batch(&mut self, node_budget: usize) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.len()).collect();
        order.sort_by_key(|&i| self.get(i).sampled_count);
        let mut chosen = Vec::new();
        let mut nodes = 0;
        for i in order {
            let n = self.get(i).sample.state.graph.num_nodes();
            if nodes + n > node_budget && !chosen.is_empty() {
                break;
            }
            nodes += n;
            chosen.push(i);
        }
        for &i in &chosen {
            self.get_mut(i).sampled_count += 1;
        }
        chosen
    }
}

#[cfg(test)]
mod tests {
    use amber_graph::FeatureSet;
    use amber_mesh::Mesh2;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    /// A strip of `n` triangles (so `n` graph nodes).
    fn sample(n: usize) -> Sample<2> {
        let vertices = (0..n + 2).map(|i| [(i / 2) as f64, (i % 2) as f64]).collect();
        let cells =
            (0..n as u32).flat_map(|i| if i % 2 == 0 { [i, i + 2, i + 1] } else { [i, i + 1, i + 2] }).collect();
        let mesh = Mesh2::new(vertices, cells).unwrap();
        let state = MeshState::from_columns(&FeatureSet::console(), mesh, Vec::new()).unwrap();
        Sample { state, labels: vec![1.0; n], targets: vec![1.0; n] }
    }

    fn buffer(protected: usize, capacity: usize) -> ReplayBuffer<2> {
        let mut b = ReplayBuffer::new(capacity);
        for p in 0..protected {
            b.push_protected(p, sample(2));
        }
        b
    }

    #[test]
    fn protected_entries_survive_and_the_fifo_keeps_its_capacity() {
        let mut b = buffer(3, 4);
        for k in 0..10 {
            let evicted = b.push_generated(k % 3, 1 + k % 2, sample(2));
            // The oldest generated entry leaves first.
            assert_eq!(evicted.map(|e| e.id), (k >= 4).then(|| 3 + k as u64 - 4));
            assert!(b.generated().count() <= 4);
        }
        assert_eq!(b.len(), 7);
        assert_eq!(b.protected().iter().map(|e| (e.id, e.depth)).collect::<Vec<_>>(), vec![(0, 0), (1, 0), (2, 0)]);
        assert_eq!(b.generated().map(|e| e.id).collect::<Vec<_>>(), vec![9, 10, 11, 12]);
        assert_eq!(b.depth_histogram(), vec![3, 2, 2]);
    }

    #[test]
    fn batches_take_the_least_used_within_the_node_budget() {
        let mut b = buffer(2, 10);
        b.push_generated(0, 1, sample(5));
        b.push_generated(1, 1, sample(3));
        // Nodes: 2, 2, 5, 3. Budget 8: 2 + 2 fit, 5 does not → stop (no skipping to the 3).
        assert_eq!(b.next_batch(8), vec![0, 1]);
        assert_eq!(b.next_batch(8), vec![2, 3]);
        // All used once: buffer order again.
        assert_eq!(b.next_batch(9), vec![0, 1, 2]);
        // An entry larger than the budget forms a batch alone.
        assert_eq!(b.next_batch(1), vec![3]);
        // New entries start at the mean use count.
        b.push_generated(0, 2, sample(1));
        assert_eq!(b.get(4).sampled_count, 2);
    }

    #[test]
    fn stratified_choice_is_uniform_over_depths_then_entries() {
        let mut b = buffer(2, 100);
        for _ in 0..30 {
            b.push_generated(0, 1, sample(2));
        }
        b.push_generated(1, 2, sample(2));
        b.push_generated(1, 5, sample(2));
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let draws = 6000;
        let mut per_depth = [0usize; 6];
        for _ in 0..draws {
            let i = b.choose_source(4, SourceSelection::Stratified, &mut rng).unwrap();
            per_depth[b.get(i).depth] += 1;
        }
        // Depths 0, 1, 2 a third each; depth 5 exceeds the maximum.
        for d in [0, 1, 2] {
            assert!((per_depth[d] as f64 / draws as f64 - 1.0 / 3.0).abs() < 0.03, "{per_depth:?}");
        }
        assert_eq!(per_depth[5], 0);
        // Uniform choice follows the entry counts instead: depth 1 dominates.
        let uniform = (0..draws)
            .filter(|_| b.get(b.choose_source(4, SourceSelection::Uniform, &mut rng).unwrap()).depth == 1)
            .count();
        assert!((uniform as f64 / draws as f64 - 30.0 / 33.0).abs() < 0.03);
        assert_eq!(ReplayBuffer::<2>::new(5).choose_source(4, SourceSelection::Stratified, &mut rng), None);
    }
}
