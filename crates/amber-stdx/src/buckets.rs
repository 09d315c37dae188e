//! Grouping items by a small integer key in linear time: a stable counting sort into compressed
//! rows, the adjacency tables of meshes and graphs (the elements around a vertex, the edges out
//! of a node, the facets by their smallest vertex).

/// Items grouped by a key below `num_keys`, each key's items in the order they were given: the
/// items of key `k` are `items[offsets[k]..offsets[k + 1]]`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Buckets<T> {
    /// `num_keys + 1` ascending starts, the first 0 and the last the item count.
    pub offsets: Vec<u32>,
    pub items: Vec<T>,
}

impl<T: Copy + Default> Buckets<T> {
    /// Groups `item(i)` by `key(i)` for every i below `count` (both called in ascending i; `key`
    /// twice per i, so it should be cheap). Every key must be below `num_keys`, and `count` must
    /// fit in `u32`.
    pub fn new(num_keys: usize, count: usize, key: impl Fn(usize) -> u32, mut item: impl FnMut(usize) -> T) -> Self {
        let offsets = offsets_of(num_keys, (0..count).map(&key));
        let mut next = offsets.clone();
        let mut items = vec![T::default(); count];
        for i in 0..count {
            let slot = &mut next[key(i) as usize];
            items[*slot as usize] = item(i);
            *slot += 1;
        }
        Self { offsets, items }
    }
}

impl<T> Buckets<T> {
    /// The items of `key`, in the order they were given.
    pub fn bucket(&self, key: usize) -> &[T] {
        &self.items[self.offsets[key] as usize..self.offsets[key + 1] as usize]
    }

    /// The items of `key`, to reorder within the bucket.
    pub fn bucket_mut(&mut self, key: usize) -> &mut [T] {
        &mut self.items[self.offsets[key] as usize..self.offsets[key + 1] as usize]
    }
}

/// The compressed-row starts of `keys` (each below `num_keys`): entry `k` counts the keys below
/// `k`, so a list sorted by key has key `k`'s entries at `offsets[k]..offsets[k + 1]`.
pub fn offsets_of(num_keys: usize, keys: impl IntoIterator<Item = u32>) -> Vec<u32> {
    let mut offsets = vec![0u32; num_keys + 1];
    for key in keys {
        offsets[key as usize + 1] += 1;
    }
    for k in 0..num_keys {
        offsets[k + 1] += offsets[k];
    }
    offsets
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_by_key_keeping_the_given_order() {
        let keys = [2u32, 0, 2, 3, 0, 2];
        let buckets = Buckets::new(5, keys.len(), |i| keys[i], |i| i as u32 * 10);
        assert_eq!(buckets.offsets, [0, 2, 2, 5, 6, 6]);
        assert_eq!(buckets.items, [10, 40, 0, 20, 50, 30]);
        assert_eq!(buckets.bucket(2), [0, 20, 50]);
        assert!(buckets.bucket(1).is_empty() && buckets.bucket(4).is_empty());
        assert_eq!(offsets_of(5, keys), buckets.offsets);
        assert_eq!(offsets_of(0, []), [0]);
    }
}
